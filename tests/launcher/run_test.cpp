// `tachi run` as a user runs it: the launcher starts the real executables, supervises them and
// leaves its outputs; `tachi topics|echo|status` look at a running pipeline. Domain ids 120-149
// belong to tests/launcher (docs/testing.md).
#include "paths.hpp"
#include "bus_wait.hpp"
#include "cut_lines.hpp"
#include "files.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "test_pki.hpp"
#include "tachi/bus/run_partition.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;
using tachi::test::read_json;
using tachi::test::read_text;
namespace fs = std::filesystem;

namespace {
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

std::vector<std::string> run_args(const std::string& recording, unsigned domain, const fs::path& out,
                                  std::vector<std::string> extra = {}) {
  std::vector<std::string> args{kBin + "/tachi", "run", "--recording", kRecordings + "/" + recording, "--grid", "32",
                                "--domain", std::to_string(domain), "--out", out.string(), "--headless", "--settle", "1",
                                // The grid cut reports the cells it cut (summary cut_line), which these tests check.
                                "--set", "sim.cut-mode=grid"};
  // Twice the recorded pace unless a test sets its own: no test here measures the pace, and each run
  // waits on the recording's clock (halves ~4.7 s of straight_cut's playback).
  if (std::find(extra.begin(), extra.end(), "--rate") == extra.end()) args.insert(args.end(), {"--rate", "2"});
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::size_t count_lines(const fs::path& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// Depth frames of a recording (INDEX.txt also lists accelerometer dumps).
std::size_t depth_frames(const std::string& recording) {
  std::ifstream in(kRecordings + "/" + recording + "/INDEX.txt");
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += line.starts_with("d-") ? 1 : 0;
  return n;
}

// PIDs of processes whose command line holds every one of `words` (the launcher's children).
std::vector<pid_t> find_processes(const std::vector<std::string>& words) {
  std::vector<pid_t> pids;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = read_text(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    bool all = !cmdline.empty();
    for (const auto& w : words) all = all && cmdline.find(w) != std::string::npos;
    if (all) pids.push_back(std::stoi(name));
  }
  return pids;
}

bool any_sample(const tachi_msg_RawHandSample&) { return true; }

std::string logs(const fs::path& out) {
  std::string text;
  for (const char* node : {"sensor", "filter", "sim", "viewer"})
    text += std::string("--- ") + node + ".log\n" + read_text(out / (std::string(node) + ".log"));
  return text;
}
}  // namespace

// Beside the run, the same run `--in-process`: the same nodes in one process (tachi-pipeline), each on its
// own thread and participant, on another domain; its run must be the multi-process run's (the cut line to within a cell: tests/support/cut_lines.hpp).
TEST(TachiRun, PlaysARecordingAndTheCutFollowsTheStrokeAsProcessesAndInOne) {
  tachi::test::ScratchDir out("tachi_run"), composed("tachi_run_in_process");
  ChildProcess composed_run(run_args("straight_cut", 135, composed.path(), {"--in-process"}));
  const auto r = tachi::test::run(run_args("straight_cut", 120, out.path()), 120s);
  ASSERT_EQ(r.exit_code, 0) << r.err << logs(out.path());
  EXPECT_NE(r.out.find("outputs in " + out.path().string()), std::string::npos) << r.out;
  const auto s = read_json(out / "summary.json");
  ASSERT_TRUE(s.is_object()) << r.err;
  for (const char* key : {"frames", "tracked_frames", "strokes", "cuts", "pieces", "fallen_pieces", "cut_length_m", "restarts",
                          "e2e_p50_ms", "e2e_p99_ms", "sensor_p50_ms", "sensor_p99_ms", "filter_p50_ms", "filter_p99_ms",
                          "sim_p50_ms", "sim_p99_ms", "viewer_p50_ms", "viewer_p99_ms"})
    EXPECT_TRUE(s.contains(key) && !s[key].is_null()) << key << ": " << s.dump();
  EXPECT_EQ(s["frames"], depth_frames("straight_cut")) << "every depth frame was played and counted";
  EXPECT_EQ(s["strokes"], 1);
  EXPECT_EQ(s["cuts"], 1);
  EXPECT_EQ(s["pieces"], 1) << "a slit, not a cut-off";
  EXPECT_EQ(s["restarts"], 0);
  EXPECT_GT(s["e2e_p50_ms"].get<double>(), 0.0);
  EXPECT_LE(s["e2e_p50_ms"].get<double>(), s["e2e_p99_ms"].get<double>());

  // The recorded hand sweeps camera x -0.35 .. 0.30 m at y ~ 0 (ground_truth.csv), mirrored onto the
  // cloth: world x 0.35 .. -0.30 at mid height. On a 32 x 32 grid over 1 m: columns ~6..26, row 15.5.
  // The cut must lie within one grid cell of that row, and span the sweep to within two cells.
  int min_u = 99, max_u = -1;
  for (const auto& g : s["cut_line"]) {
    const int u = g[0].get<int>(), v = g[1].get<int>();
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    EXPECT_NEAR(v, 15.5, 1.5) << "cell (" << u << ", " << v << ") of " << s["cut_line"];
  }
  EXPECT_LE(min_u, 9) << s["cut_line"];
  EXPECT_GE(max_u, 23) << s["cut_line"];

  for (const char* file : {"cloth.obj", "pattern.svg", "final.png", "video.mp4", "latency.png", "trajectory.png", "sensor.log",
                           "filter.log", "sim.log", "viewer.log", "config.json"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  EXPECT_NE(read_text(out / "cloth.obj").find("\nv "), std::string::npos) << "the simulator's exported mesh";
  EXPECT_GT(fs::file_size(out / "video.mp4"), 10'000u) << "the viewer's render of the run";
  // The trace saw the run's raw hand samples (keep-last 64: one may be overwritten if the launcher stalls).
  EXPECT_LE(count_lines(out / "trace" / "hands.csv"), depth_frames("straight_cut") + 1);
  EXPECT_GE(count_lines(out / "trace" / "hands.csv"), depth_frames("straight_cut") * 9 / 10);

  ASSERT_EQ(composed_run.wait(120s), 0) << composed_run.err() << read_text(composed / "pipeline.log");
  const auto c = read_json(composed / "summary.json");
  for (const char* key : {"frames", "tracked_frames", "strokes", "cuts", "pieces", "fallen_pieces", "cut_length_m", "restarts",
                          "e2e_p50_ms", "e2e_p99_ms", "sensor_p50_ms", "filter_p50_ms", "sim_p50_ms", "viewer_p50_ms"})
    EXPECT_TRUE(c.contains(key) && !c[key].is_null()) << key << ": " << c.dump();
  EXPECT_EQ(c["frames"], depth_frames("straight_cut"));
  EXPECT_EQ(c["restarts"], 0);
  for (const char* key : {"tracked_frames", "hand_samples", "strokes", "cuts", "pieces"})
    EXPECT_EQ(c[key], s[key]) << key << " in one process and as processes";
  EXPECT_TRUE(tachi::test::cut_lines_agree_within_a_cell(c, s)) << "in one process and as processes";
  EXPECT_EQ(read_json(composed / "config.json")["in_process"], true);
  // One process, its log naming each node's lines; the outputs are the multi-process run's.
  EXPECT_FALSE(fs::exists(composed / "sim.log"));
  const std::string log = read_text(composed / "pipeline.log");
  for (const char* node : {"[tachi-pipeline:sensor]", "[tachi-pipeline:sim]", "[tachi-pipeline:viewer]", "[tachi-pipeline:filter]"})
    EXPECT_NE(log.find(node), std::string::npos) << node << " in " << log;
  for (const char* file : {"cloth.obj", "pattern.svg", "final.png", "video.mp4", "latency.png", "trajectory.png"})
    EXPECT_TRUE(fs::exists(composed / file)) << file;
  EXPECT_GT(fs::file_size(composed / "video.mp4"), 10'000u);
}

TEST(TachiRun, TwoRunsOnDifferentDomainsDoNotSeeEachOther) {
  tachi::test::ScratchDir a("tachi_run_a"), b("tachi_run_b");
  ChildProcess run_a(run_args("straight_cut", 121, a.path()));
  ChildProcess run_b(run_args("push", 122, b.path()));
  ASSERT_EQ(run_a.wait(120s), 0) << run_a.err();
  ASSERT_EQ(run_b.wait(120s), 0) << run_b.err();
  const auto sa = read_json(a / "summary.json"), sb = read_json(b / "summary.json");
  // Each saw exactly its own recording's frames: none of the other run's samples crossed over.
  EXPECT_EQ(sa["frames"], depth_frames("straight_cut"));
  EXPECT_EQ(sb["frames"], depth_frames("push"));
  // Neither launcher's trace holds more raw samples than its own recording has frames (keep-last: a
  // sample may be overwritten under load, never appear from the other domain).
  EXPECT_LE(count_lines(a / "trace" / "hands.csv"), depth_frames("straight_cut") + 1);
  EXPECT_LE(count_lines(b / "trace" / "hands.csv"), depth_frames("push") + 1);
  EXPECT_GE(count_lines(b / "trace" / "hands.csv"), depth_frames("push") * 9 / 10);
  // The simulators got no more than their own (the first few may pass before filter and simulator match).
  EXPECT_LE(sa["hand_samples"].get<std::size_t>(), depth_frames("straight_cut"));
  EXPECT_LE(sb["hand_samples"].get<std::size_t>(), depth_frames("push"));
  EXPECT_GT(sb["hand_samples"].get<std::size_t>(), depth_frames("push") / 2);
}

TEST(TachiRun, AChildKilledMidRunIsRestartedAndTheRunCompletes) {
  tachi::test::ScratchDir out("tachi_run_kill");
  // The test waits on the sensor's samples (in every run's partition) instead of sleeping.
  tachi::bus::read_every_run();
  tachi::bus::Participant dds{123};
  tachi::bus::Reader<tachi_msg_RawHandSample> hands{dds, tachi::bus::topics::raw_hand};
  // The recorded pace: the recording lasts ~4.7 s, so the filter dies in its first second and comes back
  // (in well under a second, bench/launcher/recovery.py) before its end.
  ChildProcess run(run_args("straight_cut", 123, out.path(), {"--rate", "1"}));
  std::vector<pid_t> filters;
  for (int i = 0; i < 100 && filters.empty(); ++i) {
    std::this_thread::sleep_for(50ms);
    filters = find_processes({"tachi-filter", "--domain 123 "});
  }
  ASSERT_EQ(filters.size(), 1u);
  // Early in the run: the sensor has published 25 hand samples of the recording's 142 frames.
  ASSERT_EQ(tachi::test::wait_for_matching<tachi_msg_RawHandSample>(hands, 25, any_sample, 60s), 25) << run.err();
  ::kill(filters.front(), SIGKILL);
  ASSERT_EQ(run.wait(120s), 0) << run.err();
  EXPECT_NE(run.err().find("tachi-filter died (killed by SIGKILL)"), std::string::npos) << run.err();
  const auto s = read_json(out / "summary.json");
  EXPECT_EQ(s["restarts"], 1) << s.dump();
  EXPECT_EQ(s["frames"], depth_frames("straight_cut"));
  // The restarted filter carried on: the simulator received samples from after the restart.
  const auto filter_log = read_text(out / "filter.log");
  std::size_t starts = 0;
  for (auto at = filter_log.find("=== "); at != std::string::npos; at = filter_log.find("=== ", at + 1)) ++starts;
  EXPECT_EQ(starts, 2u) << "two starts logged: " << filter_log;
  EXPECT_GT(s["hand_samples"].get<int>(), static_cast<int>(depth_frames("straight_cut")) / 2);
}

TEST(TachiRun, AChildThatKeepsDyingStopsTheRunNamingIt) {
  tachi::test::ScratchDir out("tachi_run_dying");
  const auto bad_xml = out / "broken.xml";
  std::ofstream(bad_xml) << "<CycloneDDS><Domain><General><NotAnElement/>";
  const auto r = tachi::test::run(
      run_args("straight_cut", 124, out.path() / "run", {"--nodes", "sim", "--set", "sim.dds-config=" + bad_xml.string()}), 120s);
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("tachi-sim died 5 times within 30 s"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("  | tachi-sim: "), std::string::npos) << "its last log lines: " << r.err;
}

// SIGINT mid-run, as processes and in one process (side by side, each on its own domain).
TEST(TachiRun, SigintStopsTheRunCleanlyWithOutputsWrittenAsProcessesAndInOne) {
  struct Mode {
    unsigned domain;
    std::vector<std::string> flags;
    const char* log;
  };
  const std::vector<Mode> modes{{125, {}, "sim.log"}, {137, {"--in-process"}, "pipeline.log"}};
  // The test waits on the sensors' samples (in every run's partition) instead of sleeping.
  tachi::bus::read_every_run();
  std::vector<std::unique_ptr<tachi::test::ScratchDir>> outs;
  std::vector<std::unique_ptr<tachi::bus::Participant>> participants;
  std::vector<std::unique_ptr<tachi::bus::Reader<tachi_msg_RawHandSample>>> hands;
  std::vector<std::unique_ptr<ChildProcess>> runs;
  for (const auto& m : modes) {
    outs.push_back(std::make_unique<tachi::test::ScratchDir>("tachi_run_sigint_" + std::to_string(m.domain)));
    participants.push_back(std::make_unique<tachi::bus::Participant>(m.domain));
    hands.push_back(std::make_unique<tachi::bus::Reader<tachi_msg_RawHandSample>>(*participants.back(), tachi::bus::topics::raw_hand));
    auto flags = m.flags;
    flags.insert(flags.begin(), {"--rate", "0.5"});
    runs.push_back(std::make_unique<ChildProcess>(run_args("straight_cut", m.domain, outs.back()->path(), flags)));
  }
  for (std::size_t i = 0; i < modes.size(); ++i) {
    SCOPED_TRACE(modes[i].flags.empty() ? "processes" : "in one process");
    const std::string domain = "--domain " + std::to_string(modes[i].domain) + " ";
    // Mid-run: at least 30 of the recording's 142 frames played (the second run's came meanwhile).
    ASSERT_GE(tachi::test::wait_for_matching<tachi_msg_RawHandSample>(*hands[i], 30, any_sample, 60s), 30) << runs[i]->err();
    if (!modes[i].flags.empty()) {
      // The nodes run in one process: no tachi-sim, tachi-filter, ... of their own.
      EXPECT_EQ(find_processes({"tachi-pipeline", domain}).size(), 1u);
      for (const pid_t pid : find_processes({domain}))
        for (const char* program : {"tachi-sim", "tachi-filter", "tachi-sensor", "tachi-viewer"})
          EXPECT_NE(read_text(fs::path("/proc") / std::to_string(pid) / "comm"), std::string(program) + "\n");
    }
    runs[i]->signal(SIGINT);
    EXPECT_EQ(runs[i]->wait(20s), 0) << runs[i]->err();
    EXPECT_TRUE(find_processes({domain}).empty()) << "no node outlives the launcher";
    const fs::path out = outs[i]->path();
    const auto s = read_json(out / "summary.json");
    ASSERT_TRUE(s.is_object());
    EXPECT_EQ(s["ended"], "stopped by signal");
    EXPECT_GT(s["frames"].get<int>(), 0);
    EXPECT_LT(s["frames"].get<int>(), static_cast<int>(depth_frames("straight_cut")));
    for (const char* file : {"cloth.obj", "latency.png", "trajectory.png", modes[i].log}) EXPECT_TRUE(fs::exists(out / file)) << file;
  }
}

TEST(TachiBusTools, TopicsEchoAndStatusShowARunningPipeline) {
  tachi::test::ScratchDir out("tachi_run_tools");
  // The test waits on the sensor's samples (in every run's partition) instead of sleeping.
  tachi::bus::read_every_run();
  tachi::bus::Participant dds{126};
  tachi::bus::Reader<tachi_msg_RawHandSample> hands{dds, tachi::bus::topics::raw_hand};
  ChildProcess run(run_args("straight_cut", 126, out.path(), {"--rate", "0.5"}));
  // The pipeline is up and the sensor playing (the last node the launcher starts).
  ASSERT_GT(tachi::test::wait_for_matching<tachi_msg_RawHandSample>(hands, 1, any_sample, 60s), 0) << run.err();
  const std::string d = "126";
  const auto topics = tachi::test::run({kBin + "/tachi", "topics", "--domain", d}, 30s);
  const auto echo = tachi::test::run({kBin + "/tachi", "echo", "tachi/hand/raw", "--domain", d, "--count", "3"}, 30s);
  const auto state = tachi::test::run({kBin + "/tachi", "echo", "tachi/cloth/state", "--domain", d, "--count", "1"}, 30s);
  const auto status = tachi::test::run({kBin + "/tachi", "status", "--domain", d}, 30s);
  run.signal(SIGINT);
  run.wait(20s);

  EXPECT_EQ(topics.exit_code, 0) << topics.err;
  for (const char* text : {"tachi-sensor", "tachi-filter", "tachi-sim", "tachi-viewer", "tachi/hand/raw", "tachi::msg::RawHandSample",
                           "tachi/cloth/state", "tachi/node/status"})
    EXPECT_NE(topics.out.find(text), std::string::npos) << text << " in\n" << topics.out;

  EXPECT_EQ(echo.exit_code, 0) << echo.err;
  std::istringstream lines(echo.out);
  int samples = 0;
  for (std::string line; std::getline(lines, line); ++samples) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    ASSERT_TRUE(j.is_object()) << line;
    EXPECT_GT(j["acquired_ns"].get<std::int64_t>(), 0) << line;
  }
  EXPECT_EQ(samples, 3);
  const auto cloth = nlohmann::json::parse(state.out, nullptr, false);
  ASSERT_TRUE(cloth.is_object()) << state.out << state.err;
  // Summarised, not printed whole: 3 floats per particle, 32 x 32 of them plus those a cut duplicated.
  EXPECT_GE(cloth["positions"]["length"].get<int>(), 3 * 32 * 32) << state.out;
  EXPECT_EQ(cloth["positions"]["first"].size(), 8u) << state.out;

  EXPECT_EQ(status.exit_code, 0) << status.err;
  for (const char* text : {"tachi-sensor", "tachi-filter", "tachi-sim", "tachi-viewer", "running", "frames", "latency_p50_ms"})
    EXPECT_NE(status.out.find(text), std::string::npos) << text << " in\n" << status.out;
}

TEST(TachiRun, PrintConfigShowsTheConfigFileUnderTheFlags) {
  tachi::test::ScratchDir dir("tachi_run_config");
  std::ofstream(dir / "run.json") << R"({"grid": 96, "gate": "threshold", "sim": {"material": "denim"}, "filter": {"smoother": "none"}})";
  const auto r = tachi::test::run({kBin + "/tachi", "run", "--config", (dir / "run.json").string(), "--grid", "48", "--set",
                                   "viewer.fps=15", "--print-config"},
                                  10s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto c = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_TRUE(c.is_object()) << r.out;
  EXPECT_EQ(c["grid"], 48) << "the flag overrides the file";
  EXPECT_EQ(c["sim"]["material"], "denim");
  EXPECT_EQ(c["sim"]["pin"], "top-edge") << "the built-in default stays";
  EXPECT_EQ(c["filter"]["smoother"], "none");
  EXPECT_EQ(c["viewer"]["fps"], 15);

  const auto bad = tachi::test::run({kBin + "/tachi", "run", "--grid", "1"}, 10s);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--grid"), std::string::npos) << bad.err;
  std::ofstream(dir / "bad.json") << R"({"grid": 32, "colour": "red"})";
  const auto bad_key = tachi::test::run({kBin + "/tachi", "run", "--config", (dir / "bad.json").string()}, 10s);
  EXPECT_EQ(bad_key.exit_code, 2);
  EXPECT_NE(bad_key.err.find("\"colour\""), std::string::npos) << bad_key.err;
}

TEST(WaitingForPeers, ANodeWhosePeerDoesNotComeSaysSoEveryFewSeconds) {
  // Domain 128 has no simulator and no sensor: the viewer and the filter wait, and must say so.
  ChildProcess viewer({kBin + "/tachi-viewer", "--headless", "--domain", "128"});
  ChildProcess filter({kBin + "/tachi-filter", "--domain", "128"});
  // The viewer says it after 3 s without a cloth state, counted from its start, and loading its
  // OpenCV/Qt libraries takes a second on a loaded machine: wait for the words (10 s at most).
  const auto said = [](ChildProcess& p, const std::string& words) {
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (p.err().find(words) == std::string::npos && std::chrono::steady_clock::now() < deadline)
      p.wait_for_output("never printed", 50ms);
  };
  said(viewer, "is tachi-sim running on domain 128");
  said(filter, "waiting for tachi-sensor on domain 128");
  viewer.signal(SIGINT);
  filter.signal(SIGINT);
  EXPECT_EQ(viewer.wait(10s), 0);
  EXPECT_EQ(filter.wait(10s), 0);
  // The viewer has its own, stronger check (no cloth state, whether or not a simulator is there).
  EXPECT_NE(viewer.err().find("is tachi-sim running on domain 128"), std::string::npos) << viewer.err();
  EXPECT_NE(filter.err().find("waiting for tachi-sensor on domain 128"), std::string::npos) << filter.err();
}

TEST(TachiRun, LiveWithoutAKinectStopsTheRunWithExitCode3) {
  tachi::test::ScratchDir out("tachi_run_live");
  // As processes, and in one process beside it (its own domain: the pipelines' nodes start before the sensor
  // fails, and a second pipeline on a domain is refused), where the pipeline answers for its sensor with the
  // same code and words.
  ChildProcess composed({kBin + "/tachi", "run", "--live", "--grid", "16", "--domain", "147", "--out",
                         (out / "in-process").string(), "--headless", "--in-process"});
  const auto r = tachi::test::run({kBin + "/tachi", "run", "--live", "--grid", "16", "--domain", "129", "--out",
                                   out.path().string(), "--headless"},
                                  60s);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("tachi-sensor cannot run (exit code 3)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no Kinect"), std::string::npos) << "the sensor's own words, from its log: " << r.err;
  EXPECT_TRUE(fs::exists(out / "summary.json"));

  EXPECT_EQ(composed.wait(60s), 3) << composed.err();
  EXPECT_NE(composed.err().find("tachi-pipeline cannot run (exit code 3)"), std::string::npos) << composed.err();
  EXPECT_NE(composed.err().find("tachi-sensor: no Kinect"), std::string::npos) << composed.err();
}

// `tachi run --lossy 100`: every node drops 10% of the packets it sends (data, heartbeats,
// acknowledgements, discovery); reliable topics resend what was lost, so the recording cuts the cloth
// as a clean run does, the cut line to within a cell (a clean run beside it, on another domain).
TEST(TachiRun, ALossyLinkCutsAsTheCleanRunDoes) {
  tachi::test::ScratchDir clean("tachi_run_clean"), lossy("tachi_run_lossy");
  ChildProcess clean_run(run_args("straight_cut", 132, clean.path()));
  ChildProcess lossy_run(run_args("straight_cut", 133, lossy.path(), {"--lossy", "100"}));
  ASSERT_EQ(clean_run.wait(120s), 0) << clean_run.err();
  ASSERT_EQ(lossy_run.wait(120s), 0) << lossy_run.err() << logs(lossy.path());
  const auto sc = read_json(clean / "summary.json"), sl = read_json(lossy / "summary.json");
  EXPECT_EQ(read_json(lossy / "config.json")["lossy"], 100);
  EXPECT_NE(read_text(lossy / "cyclonedds-lossy.xml").find("<XmitLossiness>100</XmitLossiness>"), std::string::npos);
  EXPECT_NE(read_text(lossy / "sim.log").find("cyclonedds-lossy.xml"), std::string::npos) << "the nodes read it";
  EXPECT_EQ(sl["frames"], depth_frames("straight_cut")) << "every frame was played";
  EXPECT_EQ(sl["hand_samples"], sc["hand_samples"]) << "none lost for good";
  EXPECT_EQ(sl["cuts"], 1);
  EXPECT_EQ(sl["pieces"], sc["pieces"]);
  EXPECT_TRUE(tachi::test::cut_lines_agree_within_a_cell(sl, sc));
}

// Secure, as processes and in one process (side by side). In one process each node keeps its own
// participant, all with the identity "pipeline" (Cyclone gives every participant of a domain in a process
// the first one's permissions; the grant is the nodes' union).
TEST(TachiRun, SecureRunAuthenticatesEveryNodeAndTheLauncherAsProcessesAndInOne) {
  tachi::test::ScratchDir out("tachi_run_secure"), composed("tachi_run_secure_in_process");
  const std::string pki = tachi::test::test_pki("ours");
  ChildProcess composed_run(run_args("straight_cut", 138, composed.path() / "run", {"--secure", pki, "--in-process"}));
  const auto r = tachi::test::run(run_args("straight_cut", 130, out.path() / "run", {"--secure", pki}), 120s);
  ASSERT_EQ(r.exit_code, 0) << r.err << logs(out.path() / "run");
  const auto s = read_json(out / "run" / "summary.json");
  EXPECT_EQ(s["frames"], depth_frames("straight_cut")) << "the launcher (identity monitor) read the sensor's heartbeats";
  EXPECT_EQ(s["run_id"].get<std::string>().size(), 16u) << "a secure run has its own partition like any other";
  EXPECT_EQ(s["cuts"], 1);
  EXPECT_GT(s["cut_particles"].get<int>(), 5);
  EXPECT_NE(read_text(out / "run" / "sim.log").find("--secure"), std::string::npos);

  ASSERT_EQ(composed_run.wait(120s), 0) << composed_run.err() << read_text(composed / "run" / "pipeline.log");
  const auto c = read_json(composed / "run" / "summary.json");
  EXPECT_EQ(c["frames"], depth_frames("straight_cut"));
  EXPECT_EQ(c["cuts"], 1);
  EXPECT_GT(c["cut_particles"].get<int>(), 5);
  EXPECT_NE(read_text(composed / "run" / "pipeline.log").find("--identity pipeline"), std::string::npos);
}

