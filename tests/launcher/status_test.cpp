#include "tachi/launcher/status.hpp"

#include <gtest/gtest.h>

using namespace tachi::launcher;

namespace {
NodeReport report(const std::string& node, std::uint32_t pid, std::int64_t t, std::map<std::string, double> metrics) {
  NodeReport r;
  r.node = node;
  r.pid = pid;
  r.time_ns = t;
  r.state = "running";
  r.metrics = std::move(metrics);
  return r;
}
}  // namespace

TEST(StatusBoard, LineShowsTheRunFromTheHeartbeats) {
  StatusBoard board;
  EXPECT_EQ(board.line(0),
            "frames - @ - fps, tracked -%, gate -, strokes -, cuts -, pieces -, p50 ms sensor - filter - sim - viewer -, restarts 0");
  board.update(report("tachi-sensor", 1, 1, {{"frames", 200}, {"tracked_frames", 150}, {"fps", 30}, {"latency_p50_ms", 0.4}}));
  board.update(report("tachi-filter", 2, 1, {{"gate", 1}, {"gate_opened_by", 1}, {"strokes", 2}, {"latency_p50_ms", 0.9}}));
  board.update(report("tachi-sim", 3, 1, {{"cuts", 1}, {"pieces", 2}, {"latency_p50_ms", 1.5}}));
  EXPECT_EQ(board.line(1),
            "frames 200 @ 30.0 fps, tracked 75%, gate cutting/threshold, strokes 2, cuts 1, pieces 2, p50 ms sensor 0.4 "
            "filter 0.9 sim 1.5 viewer -, restarts 1");
}

// The simulator's stroke count, as summary.json's: a mouse-blade run has no filter, and its strokes still show.
TEST(StatusBoard, StrokesAreTheSimulatorsCountWhateverTheirSource) {
  StatusBoard board;
  board.update(report("tachi-filter", 2, 1, {{"strokes", 1}}));
  EXPECT_EQ(board.strokes(), 1) << "the filter's count until the simulator reports";
  board.update(report("tachi-sim", 3, 1, {{"strokes", 2}, {"cuts", 2}}));
  EXPECT_EQ(board.strokes(), 2);
  EXPECT_NE(board.line(0).find("strokes 2, cuts 2"), std::string::npos) << board.line(0);
  EXPECT_EQ(board.summary()["strokes"], 2);

  StatusBoard mouse_run;  // viewer --mouse -> sim, no filter
  mouse_run.update(report("tachi-sim", 3, 1, {{"strokes", 3}, {"cuts", 1}}));
  EXPECT_NE(mouse_run.line(0).find("strokes 3, cuts 1"), std::string::npos) << mouse_run.line(0);
}

TEST(StatusBoard, SummaryTakesCountsAndPerStageLatency) {
  StatusBoard board;
  board.update(report("tachi-sensor", 1, 1, {{"frames", 90}, {"tracked_frames", 80}, {"latency_p50_ms", 0.5}, {"latency_p99_ms", 2}}));
  board.update(report("tachi-sim", 3, 1, {{"cuts", 1}, {"pieces", 2}, {"latency_p50_ms", 1.5}, {"latency_p99_ms", 4}}));
  const auto s = board.summary();
  EXPECT_EQ(s["frames"], 90);
  EXPECT_EQ(s["tracked_frames"], 80);
  EXPECT_EQ(s["pieces"], 2);
  EXPECT_EQ(s["e2e_p50_ms"], 1.5);
  EXPECT_EQ(s["e2e_p99_ms"], 4);
  EXPECT_EQ(s["sensor_p99_ms"], 2);
  EXPECT_FALSE(s.contains("viewer_p50_ms"));
  // The viewer's own name for its figure (the age of the state it shows).
  board.update(report("tachi-viewer", 4, 1, {{"state_age_p50_ms", 20}, {"state_age_p99_ms", 40}}));
  EXPECT_EQ(board.summary()["viewer_p50_ms"], 20);
  EXPECT_EQ(board.summary()["viewer_p99_ms"], 40);
}

TEST(StatusBoard, NewestReportWinsAndARestartReplacesItsPredecessor) {
  StatusBoard board;
  board.update(report("tachi-filter", 10, 200, {{"strokes", 3}}));
  board.update(report("tachi-filter", 10, 100, {{"strokes", 2}}));  // late, older sample of the same process
  EXPECT_EQ(board.metric("filter", "strokes"), 3);
  board.update(report("tachi-filter", 11, 50, {{"strokes", 0}}));  // restarted process (its own clock origin)
  EXPECT_EQ(board.metric("filter", "strokes"), 0);
}
