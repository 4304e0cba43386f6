// Bad configs, bad flags and signals through the real executables (docs/reliability.md):
// an unreadable or empty DDS config is an error naming the file, never Cyclone's network defaults;
// a non-finite flag value is refused naming the flag; every long-running process stops within 1 s
// of SIGINT/SIGTERM whatever it is doing.
#include "paths.hpp"
#include "node_status.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <thread>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

namespace {
// Domain ids 180-189 belong to this file (docs/testing.md).
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

void write(const std::filesystem::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

TEST(BadConfig, AnEmptyDdsConfigIsAnErrorNamingTheFileNotTheNetworkDefaults) {
  tachi::test::ScratchDir dir{"ddsconfig"};
  write(dir / "empty.xml", "");
  write(dir / "blank.xml", "  \n\t\n");
  write(dir / "words.xml", "loopback please\n");
  for (const auto* name : {"empty.xml", "blank.xml"}) {
    const auto path = (dir / name).string();
    const auto r = tachi::test::run({kBin + "/tachi-filter", "--domain", "180", "--dds-config", path}, 20s);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("DDS config file " + path + " is empty"), std::string::npos) << r.err;
  }
  const auto words = (dir / "words.xml").string();
  const auto r = tachi::test::run({kBin + "/tachi-sim", "--domain", "180", "--dds-config", words, "--steps", "1"}, 20s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(words + " is not XML"), std::string::npos) << r.err;
}

TEST(BadFlags, NonFiniteValuesAreRefusedNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{kBin + "/tachi-sim", "--offline", "--size-m", "nan", "--steps", "1"}, "--size-m: nan is not a finite number"},
      {{kBin + "/tachi-sim", "--offline", "--sphere", "0", "0", "0", "inf", "--steps", "1"}, "--sphere: inf is not a finite number"},
      {{kBin + "/tachi-sim", "--offline", "--ground", "1e999", "--steps", "1"}, "--ground"},
      {{kBin + "/tachi-viewer", "--headless", "--fps", "nan", "--duration", "2"}, "--fps: nan is not a finite number"},
      {{kBin + "/tachi-sensor", "--recording", kRecordings + "/push", "--no-dds", "--rate", "NaN"}, "--rate"},
      {{kBin + "/tachi-sim", "--domain", "181", "--hand-radius", "-nan", "--steps", "1"}, "--hand-radius: -nan is not a finite number"},
  };
  for (const auto& [argv, message] : cases) {
    const auto r = tachi::test::run(argv, 20s);
    EXPECT_EQ(r.exit_code, 2) << argv[1] << " " << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
}

// The grid's range is what the machine can hold: under a 1.5 GB address-space limit, --grid 4096 (about
// 7 GB) is refused at once saying how much it needs, instead of dying of bad_alloc half a minute later.
TEST(BadFlags, AGridTooLargeForTheMachineSaysHowMuchMemoryItNeeds) {
  const auto r = tachi::test::run({"/usr/bin/prlimit", "--as=1500000000", kBin + "/tachi-sim", "--offline", "--grid", "4096",
                                   "--steps", "1"},
                                  20s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--grid"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("a 4096x4096 cloth needs about"), std::string::npos) << r.err;
  // A grid that fits still runs under the same limit.
  const auto small = tachi::test::run({"/usr/bin/prlimit", "--as=1500000000", kBin + "/tachi-sim", "--offline", "--grid", "64",
                                       "--steps", "1"},
                                      20s);
  EXPECT_EQ(small.exit_code, 0) << small.err;
}

TEST(BadFlags, TheBenchmarksAnswerHelp) {
  for (const auto* exe : {"/tachi-voice-eval", "/tachi-sensor-bench"}) {
    const auto r = tachi::test::run({kBin + exe, "--help"}, 20s);
    EXPECT_EQ(r.exit_code, 0) << exe << r.err;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << r.out;
  }
  // The benchmarks with positional numbers (bench/bench_args.hpp): before, `provot_bench --help` read a grid
  // of 0 and crashed, and `cut_bench --help` ran the benchmark.
  for (const auto* exe : {"/cut_bench", "/provot_bench", "/render_bench", "/sim_bench", "/cut_stability"}) {
    const auto r = tachi::test::run({kBin + exe, "--help"}, 20s);
    EXPECT_EQ(r.exit_code, 0) << exe << r.err;
    EXPECT_NE(r.out.find("usage: "), std::string::npos) << exe << r.out;
  }
  const std::pair<std::vector<std::string>, std::string> wrong[] = {
      {{kBin + "/provot_bench", "abc"}, "provot_bench: 'abc' is not a whole number in 4..512"},
      {{kBin + "/provot_bench", "0"}, "provot_bench: '0' is not a whole number"},
      {{kBin + "/cut_bench", "5", "0", "99"}, "cut_bench: '99' is not a whole number in 1..64"},
      {{kBin + "/cut_bench", "5x"}, "cut_bench: '5x' is not a whole number"},
      {{kBin + "/render_bench", "--frames", "-3"}, "render_bench --frames: '-3' is not a whole number"},
      {{kBin + "/render_bench", "--fps", "30"}, "render_bench: unknown argument '--fps'"},
      {{kBin + "/sim_bench", "--steps", "many"}, "sim_bench --steps: 'many' is not a whole number"},
      {{kBin + "/sim_bench", "--grids", "64,12x"}, "sim_bench --grids: '12x' is not a whole number in 2..1024"},
      {{kBin + "/cut_stability", "--grid", "1"}, "cut_stability --grid: '1' is not a whole number in 4..512"}};
  for (const auto& [argv, message] : wrong) {
    const auto r = tachi::test::run(argv, 20s);
    EXPECT_EQ(r.exit_code, 2) << argv[0] << " " << argv[1] << r.out << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
}

// tachi-sensor-bench on a folder without recordings (a tree that takes its recordings from another's,
// TACHI_RECORDINGS_FROM, has an empty build/recordings) printed its header and crashed on the summary of no frames.
TEST(BadFlags, TheSensorBenchNamesAFolderWithoutRecordings) {
  tachi::test::ScratchDir dir{"bench_empty"};
  const auto empty = tachi::test::run({kBin + "/tachi-sensor-bench", dir.path().string(), "1"}, 20s);
  EXPECT_EQ(empty.exit_code, 1) << empty.out << empty.err;
  EXPECT_NE(empty.err.find(dir.path().string() + ": no recordings in it"), std::string::npos) << empty.err;
  const auto missing = tachi::test::run({kBin + "/tachi-sensor-bench", (dir.path() / "nope").string(), "1"}, 20s);
  EXPECT_EQ(missing.exit_code, 2) << missing.out << missing.err;
  EXPECT_NE(missing.err.find("recordings: Directory does not exist"), std::string::npos) << missing.err;
}

// Sends `signo` to a running child and returns how long it took to exit; the exit code must be 0.
std::chrono::milliseconds signal_and_time_exit(ChildProcess& child, int signo) {
  const auto t0 = std::chrono::steady_clock::now();
  child.signal(signo);
  const int rc = child.wait(10s);
  const auto took = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
  EXPECT_EQ(rc, 0) << child.err();
  return took;
}

// Starts `argv`, lets it get busy for `settle` (these waits have no heartbeat: the sensor without DDS),
// then signals it.
std::chrono::milliseconds stop_time(std::vector<std::string> argv, int signo, std::chrono::milliseconds settle) {
  ChildProcess child(std::move(argv));
  std::this_thread::sleep_for(settle);
  EXPECT_TRUE(child.running()) << child.err();
  return signal_and_time_exit(child, signo);
}

// A copy of a bundled recording's first frames whose host time jumps by an hour after the third.
std::filesystem::path jumping_recording(const tachi::test::ScratchDir& dir) {
  const auto src = std::filesystem::path(kRecordings) / "push";
  std::ifstream index(src / "INDEX.txt");
  std::string first;
  while (std::getline(index, first) && first.rfind("d-", 0) != 0) {
  }
  const auto out = dir / "jumping";
  std::filesystem::create_directories(out);
  std::ofstream new_index(out / "INDEX.txt");
  for (int i = 0; i < 6; ++i) {
    const std::string name = "d-" + std::to_string(1'700'000'000 + (i < 3 ? 0 : 3600)) + ".0" + std::to_string(i) +
                             "0000-" + std::to_string(i) + ".pgm";
    std::filesystem::copy_file(src / first, out / name);
    new_index << name << '\n';
  }
  return out;
}

TEST(Signals, PacedPlaybackStopsWithinASecondWhateverItIsWaitingFor) {
  tachi::test::ScratchDir dir{"signals"};
  const auto jumping = jumping_recording(dir);
  const auto csv = (dir / "hands.csv").string();
  // Host time jumps by an hour: the sensor sleeps for it, and must still stop.
  EXPECT_LT(stop_time({kBin + "/tachi-sensor", "--recording", jumping.string(), "--rate", "1", "--no-dds", "--csv", csv},
                      SIGTERM, 1500ms),
            1000ms);
  std::ifstream rows(csv);
  std::string line;
  int n = 0;
  while (std::getline(rows, line)) ++n;
  EXPECT_EQ(n, 1 + 3) << "the header and the three frames before the jump";
  // --rate 1e-9: the second frame is due in a year.
  EXPECT_LT(stop_time({kBin + "/tachi-sensor", "--recording", kRecordings + "/push", "--rate", "1e-9", "--no-dds"}, SIGINT,
                      1000ms),
            1000ms);
  // Waiting for DDS readers that never come.
  EXPECT_LT(stop_time({kBin + "/tachi-sensor", "--recording", kRecordings + "/push", "--domain", "182", "--wait-readers",
                       "3"},
                      SIGTERM, 1000ms),
            1000ms);
}

// Starts a bus node and signals it once its heartbeat says it runs its loop. (A fixed settle time made
// this test flaky on a loaded machine: the viewer loads ~260 shared libraries, and a signal that came
// while it was still loading them or joining the domain timed its start-up, not its stop.)
std::chrono::milliseconds stop_time_when_running(std::vector<std::string> argv, const std::string& node, int signo) {
  tachi::bus::Participant dds{183};
  tachi::bus::Reader<tachi_msg_NodeStatus> status{dds, tachi::bus::topics::node_status};
  ChildProcess child(std::move(argv));
  EXPECT_TRUE(tachi::test::wait_for_status(status, node, [](const tachi_msg_NodeStatus& s) {
    return s.state == tachi_msg_NODE_RUNNING || s.state == tachi_msg_NODE_DEGRADED;
  }, 30s)) << node << " never said it runs: " << child.err();
  return signal_and_time_exit(child, signo);
}

TEST(Signals, TheBusNodesStopWithinASecond) {
  EXPECT_LT(stop_time_when_running({kBin + "/tachi-viewer", "--headless", "--domain", "183", "--fps", "1"}, "tachi-viewer", SIGTERM),
            1000ms);
  EXPECT_LT(stop_time_when_running({kBin + "/tachi-filter", "--domain", "183"}, "tachi-filter", SIGINT), 1000ms);
  EXPECT_LT(stop_time_when_running({kBin + "/tachi-sim", "--domain", "183", "--grid", "32"}, "tachi-sim", SIGTERM), 1000ms);
}

}  // namespace
