#include "tachi/filter/hand_csv.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace tachi::filter {
namespace {

TEST(HandCsv, ReadsTheSensorsColumns) {
  std::istringstream in(
      "frame,stamp_ns,x,y,z,u,v,tracked,confidence\n"
      "0,1000,0.1,-0.2,1.05,300,200,1,0.9\n"
      "1,2000,nan,nan,nan,0,0,0,0\n");
  const HandCsv csv = read_hand_csv(in);
  ASSERT_EQ(csv.samples.size(), 2U);
  EXPECT_TRUE(csv.skipped.empty());
  EXPECT_EQ(csv.samples[0].stamp_ns, 1000);
  EXPECT_TRUE(csv.samples[0].tracked);
  EXPECT_TRUE(csv.samples[0].position_m.isApprox(Eigen::Vector3f(0.1F, -0.2F, 1.05F)));
  EXPECT_FLOAT_EQ(csv.samples[0].confidence, 0.9F);
  EXPECT_FALSE(csv.samples[1].tracked);
}

TEST(HandCsv, SkipsBadRowsAndSaysWhich) {
  std::istringstream in(
      "frame,stamp_ns,x,y,z,u,v,tracked,confidence\r\n"
      "0,1000,0.1,-0.2,1.05,300,200,1,0.9\r\n"
      "1,abc,0.1,-0.2,1.05,300,200,1,0.9\n"
      "2,3000,0.1\n"
      "3,4000,0.1,oops,1.0,300,200,1,0.9\n"
      "4,5000,0.1,0.2,1.0,300,200,maybe,0.9\n"
      "5,6000,0.1,0.2,1.0,300,200,true,0.9\n");
  const HandCsv csv = read_hand_csv(in);
  ASSERT_EQ(csv.samples.size(), 2U);
  EXPECT_EQ(csv.samples[1].frame, 5U);
  ASSERT_EQ(csv.skipped.size(), 4U);
  EXPECT_NE(csv.skipped[0].find("line 3"), std::string::npos);
}

TEST(HandCsv, AHeaderWithoutRequiredColumnsIsAnError) {
  std::istringstream in("frame,x,y,z\n0,1,2,3\n");
  EXPECT_THROW(read_hand_csv(in), std::runtime_error);
  std::istringstream empty("");
  EXPECT_THROW(read_hand_csv(empty), std::runtime_error);
}

TEST(HandCsv, WritesTheStrokeColumns) {
  std::ostringstream out;
  write_stroke_csv_header(out);
  StrokeSample s;
  s.frame = 3;
  s.stamp_ns = 99;
  s.tracked = true;
  s.position_m = {0.5F, 0.25F, -0.125F};
  s.camera_position_m = {1, 2, 3};
  s.gate = GateOutput::Cutting;
  s.stroke_id = 2;
  write_stroke_csv_row(out, s, false);
  write_stroke_csv_row(out, s, true);
  s.tracked = false;
  s.gate = GateOutput::Idle;
  write_stroke_csv_row(out, s, false);
  EXPECT_EQ(out.str(),
            "frame,stamp_ns,x,y,z,gate,stroke_id\n"
            "3,99,0.500000,0.250000,-0.125000,1,2\n"
            "3,99,1.000000,2.000000,3.000000,1,2\n"
            "3,99,nan,nan,nan,0,2\n");
}

}  // namespace
}  // namespace tachi::filter
