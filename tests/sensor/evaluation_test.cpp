// tachi-sensor-eval's evaluation without the process: the seed range, a CSV pair scored and checked against
// limits (text and JSON), a randomized clip scored and listed frame by frame.
#include "tachi/sensor/evaluation.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sstream>

#include "test_util.hpp"

namespace tachi::sensor {
namespace {

TEST(Evaluation, SeedRangesAreFirstDotDotLastOrOneSeed) {
  const auto range = parse_seed_range("3..7");
  ASSERT_TRUE(range);
  EXPECT_EQ(range->first, 3U);
  EXPECT_EQ(range->last, 7U);
  const auto one = parse_seed_range("100001");
  ASSERT_TRUE(one);
  EXPECT_EQ(one->first, 100001U);
  EXPECT_EQ(one->last, 100001U);
  for (const char* bad : {"", "7..3", "1..", "..4", "a..b", "1...4", "-1", "1..2x", "99999999999999999999999"})
    EXPECT_FALSE(parse_seed_range(bad)) << bad;
}

// Three truth frames (visible, visible, hidden) and the hand 2 mm off, tracked in the first two and a
// phantom in the third when `phantom`.
void write_pair(const test::ScratchDir& dir, bool phantom) {
  test::write_text(dir.path() / "truth.csv", "frame,stamp_ns,x,y,z,visible\n0,0,0,0,1,1\n1,0,0,0,1,1\n2,0,0,0,1,0\n");
  std::ostringstream hands;
  hands << kHandCsvHeader << '\n';
  HandObservation h;
  h.tracked = true;
  h.position_m = {0.002F, 0.0F, 1.0F};
  write_hand_row(hands, 0, 0, h);
  write_hand_row(hands, 1, 0, h);
  write_hand_row(hands, 2, 0, phantom ? h : HandObservation{});
  test::write_text(dir.path() / "hands.csv", hands.str());
}

TEST(Evaluation, ACsvPairIsScoredAndMissedLimitsExitOne) {
  test::ScratchDir dir("evaluation");
  write_pair(dir, false);
  EvaluationOptions options;
  options.hands_csv = (dir.path() / "hands.csv").string();
  options.truth_csv = (dir.path() / "truth.csv").string();
  options.limits.max_rms_m = 0.01;
  options.limits.min_tracked_ratio = 0.99;
  options.limits.max_phantoms = 0;
  std::ostringstream out, err;
  EXPECT_EQ(run_evaluation(options, out, err), 0);
  EXPECT_NE(out.str().find("visible 2, tracked 2: tracked ratio 1.0000"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("RMS 3D error 2.00 mm"), std::string::npos) << out.str();
  EXPECT_EQ(err.str(), "");

  options.limits.max_rms_m = 0.001;
  EXPECT_EQ(run_evaluation(options, out, err), 1) << "2 mm over a 1 mm limit";

  write_pair(dir, true);
  options.limits.max_rms_m = 0.01;
  options.json = true;
  std::ostringstream json_out;
  EXPECT_EQ(run_evaluation(options, json_out, err), 1) << "one phantom over --max-phantoms 0";
  const auto json = nlohmann::json::parse(json_out.str());
  EXPECT_EQ(json["phantoms"], 1);
  EXPECT_EQ(json["truth_frames"], 3);
  EXPECT_NEAR(json["rms_m"].get<double>(), 0.002, 1e-6);
}

TEST(Evaluation, AMissingFileIsAnErrorNamingIt) {
  EvaluationOptions options;
  options.hands_csv = "/nonexistent/hands.csv";
  options.truth_csv = "/nonexistent/truth.csv";
  std::ostringstream out, err;
  try {
    run_evaluation(options, out, err);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/"), std::string::npos) << e.what();
  }
}

TEST(Evaluation, ARandomClipIsScoredAndListedFrameByFrame) {
  EvaluationOptions options;
  options.random = SeedRange{100001, 100001};
  options.json = true;
  options.report_only = true;
  std::ostringstream out, err;
  EXPECT_EQ(run_evaluation(options, out, err), 0) << "--report-only";
  const auto json = nlohmann::json::parse(out.str());
  ASSERT_EQ(json["clips"].size(), 1U);
  const auto& clip = json["clips"][0];
  EXPECT_EQ(clip["seed"], 100001);
  EXPECT_EQ(json["summary"]["clips"], 1);
  EXPECT_EQ(json["summary"]["visible"], clip["visible"]);
  const auto frames = clip["frames"].get<std::size_t>();
  EXPECT_GT(frames, 0U);

  options.report_only = false;
  std::ostringstream again;
  EXPECT_EQ(run_evaluation(options, again, err), json["summary"]["passed"].get<bool>() ? 0 : 1)
      << "without --report-only the exit code is the acceptance";

  EvaluationOptions listing;
  listing.frames = 100001;
  std::ostringstream csv;
  EXPECT_EQ(run_evaluation(listing, csv, err), 0);
  std::istringstream lines(csv.str());
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "frame,raised,visible,x,y,z,tracked,hx,hy,hz,error_m");
  std::size_t rows = 0;
  while (std::getline(lines, line)) ++rows;
  EXPECT_EQ(rows, frames) << "one row per frame of the clip";
}

}  // namespace
}  // namespace tachi::sensor
