#include "tachi/sensor/hand_csv.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include "test_util.hpp"

namespace tachi::sensor {
namespace {

TEST(HandCsv, WritesTheContractColumnsAndReadsThemBack) {
  test::ScratchDir dir("csv");
  std::ostringstream out;
  out << kHandCsvHeader << '\n';
  HandObservation h;
  h.tracked = true;
  h.position_m = {0.1f, -0.2f, 0.98f};
  h.u = 400.5f;
  h.v = 100.25f;
  h.confidence = 0.9f;
  write_hand_row(out, 7, 1'700'000'000'233'333'000LL, h);
  write_hand_row(out, 8, 1'700'000'000'266'667'000LL, HandObservation{});
  EXPECT_EQ(out.str().substr(0, out.str().find('\n')), "frame,stamp_ns,x,y,z,u,v,tracked,confidence");
  test::write_text(dir.path() / "h.csv", out.str());
  const auto rows = read_hand_csv(dir.path() / "h.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].frame, 7u);
  EXPECT_EQ(rows[0].stamp_ns, 1'700'000'000'233'333'000LL);
  EXPECT_NEAR(rows[0].position.z(), 0.98, 1e-6);
  EXPECT_NEAR(rows[0].u, 400.5, 1e-3);
  EXPECT_TRUE(rows[0].tracked);
  EXPECT_FALSE(rows[1].tracked);
}

TEST(Evaluation, CountsRmsTrackedRatioAndPhantoms) {
  std::vector<TruthRow> truth(5);
  std::vector<HandRow> hands(5);
  for (std::size_t i = 0; i < 5; ++i) {
    truth[i].frame = hands[i].frame = i;
    truth[i].position = {0, 0, 1};
    hands[i].position = {0, 0, 1};
  }
  truth[0].visible = false;  // hand tracked here: a phantom
  hands[0].tracked = true;
  for (std::size_t i = 1; i < 5; ++i) truth[i].visible = true;
  hands[1].tracked = true;
  hands[1].position = {0.003, 0, 1};
  hands[2].tracked = true;
  hands[2].position = {0, 0.004, 1};
  hands[3].tracked = false;  // missed
  hands.pop_back();          // frame 4 has no row at all
  const Evaluation e = evaluate(hands, truth);
  EXPECT_EQ(e.truth_frames, 5u);
  EXPECT_EQ(e.missing_frames, 1u);
  EXPECT_EQ(e.visible, 4u);
  EXPECT_EQ(e.tracked_visible, 2u);
  EXPECT_DOUBLE_EQ(e.tracked_ratio, 0.5);
  EXPECT_EQ(e.phantoms, 1u);
  EXPECT_NEAR(e.rms_m, std::sqrt((0.003 * 0.003 + 0.004 * 0.004) / 2), 1e-12);
  EXPECT_NEAR(e.max_m, 0.004, 1e-12);
}

TEST(HandCsv, BadFilesNameLineAndColumn) {
  test::ScratchDir dir("badcsv");
  const auto error = [&](const std::string& text, bool truth) {
    test::write_text(dir.path() / "x.csv", text);
    try {
      if (truth) {
        read_truth_csv(dir.path() / "x.csv");
      } else {
        read_hand_csv(dir.path() / "x.csv");
      }
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("frame,x,y,z\n", true).find("no \"visible\" column"), std::string::npos);
  EXPECT_NE(error("frame,x,y,z,visible\n0,1,2,3,1\n1,a,2,3,1\n", true).find("line 3, column \"x\": not a number"), std::string::npos);
  EXPECT_NE(error("frame,x,y,z,visible\n0,1,2,3,2\n", true).find("must be 0 or 1"), std::string::npos);
  EXPECT_NE(error("frame,x,y,z,visible\n0,1,2\n", true).find("missing"), std::string::npos);
  EXPECT_NE(error("", false).find("empty file"), std::string::npos);
  EXPECT_EQ(error("frame,stamp_ns,x,y,z,u,v,visible\n0,5,1,2,3,4,5,1\n", true), "no error");
}

}  // namespace
}  // namespace tachi::sensor
