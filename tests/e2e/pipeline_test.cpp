// The whole pipeline as separate processes on one DDS domain: tachi-sensor plays a bundled
// recording, tachi-filter smooths and gates it, tachi-sim cuts the cloth, tachi-viewer draws it
// headless. Checks what comes out: the cut in the simulator's summary and the viewer's image. The
// same four command lines composed in one process (tachi-pipeline, `tachi run --in-process`) must cut
// the same way.
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <future>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

namespace {
// Domain ids 90-99 belong to this file (docs/testing.md).
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

struct Pipeline {
  tachi::test::ScratchDir scratch{"e2e"};
  std::filesystem::path out = scratch.path();
  nlohmann::json summary;
  int sensor_exit = -2, filter_exit = -2, sim_exit = -2, viewer_exit = -2;
  std::string logs;
};

// The stages' command lines, consumers first (program name, then its arguments). The sensor plays at
// twice the recorded pace: nothing here measures it, and the run waits on the recording's clock.
std::vector<std::vector<std::string>> stages(const Pipeline& p, const std::string& recording, unsigned domain) {
  const std::string d = std::to_string(domain);
  return {{"tachi-sim", "--grid", "32", "--pin", "top-edge", "--domain", d, "--exit-when-idle", "2", "--export", p.out.string()},
          {"tachi-viewer", "--headless", "--domain", d, "--snapshot", (p.out / "final.png").string(), "--fps", "10",
           "--exit-when-idle", "3"},
          {"tachi-filter", "--domain", d, "--gate", "threshold"},
          {"tachi-sensor", "--recording", kRecordings + "/" + recording, "--rate", "2", "--domain", d, "--wait-readers", "1"}};
}

std::vector<std::string> process(std::vector<std::string> stage) {
  stage.front() = kBin + "/" + stage.front();
  return stage;
}

void run_pipeline(Pipeline& p, const std::string& recording, unsigned domain) {
  const auto s = stages(p, recording, domain);
  ChildProcess sim(process(s[0]));
  ChildProcess viewer(process(s[1]));
  ChildProcess filter(process(s[2]));
  ChildProcess sensor(process(s[3]));
  p.sensor_exit = sensor.wait(120s);
  p.sim_exit = sim.wait(60s);
  p.viewer_exit = viewer.wait(30s);
  filter.signal(SIGINT);
  p.filter_exit = filter.wait(20s);
  p.logs = "sensor: " + sensor.err() + "\nfilter: " + filter.err() + "\nsim: " + sim.err() + "\nviewer: " + viewer.err();
  std::ifstream in(p.out / "summary.json");
  if (in) p.summary = nlohmann::json::parse(in, nullptr, false);
}

// tachi-pipeline -- tachi-sim ... -- tachi-viewer ... : it ends by itself once sensor, sim and viewer
// are done, and stops the filter.
void run_in_one_process(Pipeline& p, const std::string& recording, unsigned domain) {
  std::vector<std::string> argv{kBin + "/tachi-pipeline"};
  for (const auto& stage : stages(p, recording, domain)) {
    argv.push_back("--");
    argv.insert(argv.end(), stage.begin(), stage.end());
  }
  ChildProcess pipeline(argv);
  const int exit_code = pipeline.wait(120s);
  p.sensor_exit = p.filter_exit = p.sim_exit = p.viewer_exit = exit_code;
  p.logs = "pipeline: " + pipeline.err();
  std::ifstream in(p.out / "summary.json");
  if (in) p.summary = nlohmann::json::parse(in, nullptr, false);
}

void expect_the_cut_along_the_stroke(const Pipeline& p) {
  EXPECT_EQ(p.sensor_exit, 0) << p.logs;
  EXPECT_EQ(p.filter_exit, 0) << p.logs;
  EXPECT_EQ(p.sim_exit, 0) << p.logs;
  EXPECT_EQ(p.viewer_exit, 0) << p.logs;
  ASSERT_TRUE(p.summary.is_object()) << p.logs;
  EXPECT_GT(p.summary["hand_samples"].get<int>(), 60) << p.logs;
  EXPECT_GT(p.summary["cut_particles"].get<int>(), 5) << p.logs;
  // The gate closed the stroke while the pipeline ran (the simulator reports each stroke as it closes).
  EXPECT_NE(p.logs.find("stroke 1 cut"), std::string::npos) << p.logs;
  EXPECT_EQ(p.summary["pieces"], 1) << "a slit, not a cut-off: the hand's retreat must not cut";
  // The recorded hand sweeps camera x -0.35 .. 0.30 m at y ~ 0: mirrored, world x 0.35 .. -0.30 at the
  // cloth's middle height. On a 32 x 32 grid over 1 m that is columns ~6..26, rows near 15.5.
  int min_u = 99, max_u = -1, min_v = 99, max_v = -1;
  for (const auto& g : p.summary["cut_line"]) {
    min_u = std::min(min_u, g[0].get<int>());
    max_u = std::max(max_u, g[0].get<int>());
    min_v = std::min(min_v, g[1].get<int>());
    max_v = std::max(max_v, g[1].get<int>());
  }
  EXPECT_LE(min_u, 9) << p.summary["cut_line"];
  EXPECT_GE(max_u, 23) << p.summary["cut_line"];
  EXPECT_GE(min_v, 12) << p.summary["cut_line"];
  EXPECT_LE(max_v, 19) << p.summary["cut_line"];
  EXPECT_TRUE(std::filesystem::exists(p.out / "final.png")) << p.logs;
}
}  // namespace

// Side by side on their own domains: each run mostly waits on the recording's clock.
TEST(Pipeline, AStraightHandStrokeCutsTheClothAlongItsPathAsProcessesAndInOne) {
  Pipeline processes, composed;
  auto composed_run = std::async(std::launch::async, [&composed] { run_in_one_process(composed, "straight_cut", 91); });
  run_pipeline(processes, "straight_cut", 90);
  composed_run.get();
  {
    SCOPED_TRACE("as processes");
    expect_the_cut_along_the_stroke(processes);
  }
  SCOPED_TRACE("in one process");
  expect_the_cut_along_the_stroke(composed);
  EXPECT_NE(composed.logs.find("[tachi-pipeline:filter] [info] stopping"), std::string::npos) << "the filter was stopped: " << composed.logs;
}

// tachi-pipeline's command line, as `tachi run --in-process` or a user writes it: a stage mode without the
// bus, an unknown program and no stage at all are usage errors (exit 2) that name what is wrong.
TEST(Pipeline, StagesThatCannotJoinTheBusAreRefusedNamingThem) {
  tachi::test::ScratchDir dir("e2e_refused");
  std::ofstream(dir / "cloth.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "hand.csv") << "frame,stamp_ns,x,y,z,u,v,tracked,confidence\n";
  const auto pipeline = [](std::vector<std::string> args) {
    args.insert(args.begin(), kBin + "/tachi-pipeline");
    return tachi::test::run(args, 30s);
  };
  const std::vector<std::pair<std::vector<std::string>, std::string>> refused{
      {{"--", "tachi-sim", "--offline", "--grid", "8"}, "tachi-sim --offline runs without the bus; run it alone"},
      {{"--", "tachi-filter", "--offline", "--hands", (dir / "hand.csv").string(), "--out", (dir / "s.csv").string()}, "tachi-filter --offline runs without the bus"},
      {{"--", "tachi-viewer", "--mesh", (dir / "cloth.obj").string()}, "tachi-viewer --mesh shows a file, not the bus"},
      {{"--", "tachi-simulator"}, "tachi-simulator: not a stage"},
      {{}, "no stage given"}};
  for (const auto& [args, words] : refused) {
    const auto r = pipeline(args);
    EXPECT_EQ(r.exit_code, 2) << words << "\n" << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
  }
}
