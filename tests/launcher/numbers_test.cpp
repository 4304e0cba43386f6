// `tachi run`'s figures count what their names say, and a mistake in its flags is named before any
// node starts. Through the user's path: the real launcher and nodes on the bundled recordings.
// Domain ids 210-219.
#include "paths.hpp"
#include "files.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/mount.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
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
const std::string kSource = tachi::test::source_dir();

std::vector<std::string> run_args(const std::string& recording, unsigned domain, const fs::path& out,
                                  std::vector<std::string> extra = {}) {
  std::vector<std::string> args{kBin + "/tachi", "run",   "--recording", recording, "--domain", std::to_string(domain),
                                "--out",         out.string(), "--headless", "--settle",  "1.5",
                                // Twice the recorded pace: no test here measures it, and each run waits on the recording's clock.
                                "--rate",        "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::string logs(const fs::path& out) {
  std::string text;
  for (const char* node : {"sensor", "filter", "sim", "viewer", "plot"})
    text += std::string("--- ") + node + ".log\n" + read_text(out / (std::string(node) + ".log"));
  return text;
}

// A copy of a bundled recording that stops after its first `frames` depth frames (the files are linked).
fs::path truncated_recording(const std::string& name, std::size_t frames, const fs::path& dir) {
  const fs::path from = fs::path(kRecordings) / name;
  fs::create_directories(dir);
  std::ifstream in(from / "INDEX.txt");
  std::ofstream index(dir / "INDEX.txt");
  std::size_t depth = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("d-") && ++depth > frames) break;
    index << line << '\n';
    fs::create_symlink(from / line, dir / line);
  }
  for (const auto& entry : fs::directory_iterator(from))
    if (entry.path().extension() != ".pgm" && entry.path().extension() != ".dump" && entry.path().filename() != "INDEX.txt")
      fs::create_symlink(entry.path(), dir / entry.path().filename());
  return dir;
}

}  // namespace

// A --set typo used to be found by the simulator 7.6 s into the run, which then printed a zeroed
// headline as if it had run.
TEST(TachiRunPreflight, ANodeFlagTypoIsNamedBeforeAnyNodeStarts) {
  tachi::test::ScratchDir out("numbers_typo");
  const auto r = tachi::test::run(
      run_args(kRecordings + "/top_edge", 210, out.path(), {"--set", "sim.materal=denim"}), 60s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--set sim.materal=denim"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tachi-sim"), std::string::npos) << "the node's own reason: " << r.err;
  EXPECT_EQ(r.out, "") << "no headline: nothing ran";
  for (const char* log : {"sim.log", "sensor.log", "viewer.log", "filter.log"}) EXPECT_FALSE(fs::exists(out / log)) << log;
}

TEST(TachiRunPreflight, AnOutUnderAFileIsNamed) {
  tachi::test::ScratchDir dir("numbers_out_file");
  std::ofstream(dir / "a_file") << "x";
  const auto r = tachi::test::run(run_args(kRecordings + "/top_edge", 211, dir / "a_file" / "run"), 60s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("tachi run: --out " + (dir / "a_file" / "run").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is a file"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("filesystem error"), std::string::npos) << "no raw exception: " << r.err;
  EXPECT_EQ(r.out, "");
}

// A folder without room for the run's outputs (a 256 KB tmpfs: the video alone needs more) is refused
// before the run, naming --out; without root (no mount), an unwritable folder is. (Every other run here
// passes the same check on the temp folder.)
TEST(TachiRunPreflight, AnOutWithoutRoomOrWritePermissionIsRefused) {
  tachi::test::ScratchDir dir("numbers_out_full");
  const fs::path small = dir / "small";
  fs::create_directories(small);
  if (::geteuid() == 0) {
    if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=256k") != 0) GTEST_SKIP() << "mount not permitted here";
    const auto r = tachi::test::run(run_args(kRecordings + "/top_edge", 212, small / "run"), 60s);
    ::umount2(small.c_str(), MNT_DETACH);
    EXPECT_EQ(r.exit_code, 5) << r.err;  // disk full
    EXPECT_NE(r.err.find("tachi run: --out " + (small / "run").string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("free"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
  } else {
    fs::permissions(small, fs::perms::owner_read | fs::perms::owner_exec);
    const auto r = tachi::test::run(run_args(kRecordings + "/top_edge", 212, small / "run"), 60s);
    fs::permissions(small, fs::perms::owner_all);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("tachi run: --out"), std::string::npos) << r.err;
  }
}

// top_edge: the hand's first stroke never reaches the cloth, the second cuts it once. The simulator
// used to count a cut per closed stroke (2); a stroke that cut nothing is no cut.
TEST(TachiRunNumbers, OneVisibleCutCountsOneAndEverySummaryKeyIsDocumented) {
  tachi::test::ScratchDir out("numbers_top_edge");
  const auto r = tachi::test::run(run_args(kRecordings + "/top_edge", 213, out.path()), 150s);
  ASSERT_EQ(r.exit_code, 0) << r.err << logs(out.path());
  const auto s = read_json(out / "summary.json");
  ASSERT_TRUE(s.is_object());
  EXPECT_EQ(s["cuts"], 1) << "sim.log: " << read_text(out / "sim.log");
  EXPECT_GT(s["cut_length_m"].get<double>(), 0.3);
  EXPECT_EQ(s["rejected_inputs"], 0) << "a clean run rejects nothing: " << logs(out.path());
  // The headline is the summary's.
  const auto headline = nlohmann::json::parse(r.out.substr(0, r.out.find('\n')), nullptr, false);
  ASSERT_TRUE(headline.is_object()) << r.out;
  EXPECT_EQ(headline["cuts"], s["cuts"]);

  const std::string docs = read_text(fs::path(kSource) / "docs" / "cli.md");
  const auto documented = [&](const std::string& word) { return docs.find("`" + word + "`") != std::string::npos; };
  for (const auto& [key, value] : s.items()) {
    bool found = documented(key);
    for (const char* stage : {"sensor", "filter", "sim", "viewer"})
      for (const char* p : {"_p50_ms", "_p99_ms"})
        if (key == std::string(stage) + p) found = found || documented(std::string("<stage>") + p);
    EXPECT_TRUE(found) << "summary.json key `" << key << "` is not documented in docs/cli.md";
  }

  // latency.png draws the stages' figures the summary has, not other delays under their names.
  const std::string plot = read_text(out / "plot.log");
  for (const char* stage : {"sensor", "filter", "sim", "viewer"}) {
    const std::string key = std::string(stage) + "_p99_ms";
    if (s[key].is_null()) continue;
    char expected[96];
    std::snprintf(expected, sizeof expected, "latency.png: %s p50 %.1f ms p99 %.1f ms", stage,
                  s[std::string(stage) + "_p50_ms"].get<double>(), s[key].get<double>());
    EXPECT_NE(plot.find(expected), std::string::npos) << expected << " in plot.log:\n" << plot;
  }
  // pattern.svg: one path per piece, every subpath of it closed (the rim, and a hole's rim), no loose segments.
  const std::string svg = read_text(out / "pattern.svg");
  std::size_t paths = 0;
  for (auto at = svg.find("id=\"piece_"); at != std::string::npos; at = svg.find("id=\"piece_", at + 1), ++paths) {
    const auto d = svg.find(" d=\"", at) + 4;
    const std::string path = svg.substr(d, svg.find('"', d) - d);
    const auto moves = std::count(path.begin(), path.end(), 'M');
    EXPECT_GE(moves, 1);
    EXPECT_LE(moves, 3) << "the rim and at most a hole or two, not loose segments";
    EXPECT_EQ(std::count(path.begin(), path.end(), 'Z'), moves) << "every outline closed";
  }
  EXPECT_EQ(paths, s["pieces"].get<std::size_t>());
  // The viewer's `p` snapshots go to --out.
  EXPECT_NE(read_text(out / "viewer.log").find("--snapshot-dir " + out.path().string()), std::string::npos);
}

// The recording ends while the hand is still cutting: the stroke never closes, yet it cut the cloth.
TEST(TachiRunNumbers, AStrokeStillOpenAtTheEndCountsAsACut) {
  tachi::test::ScratchDir dir("numbers_open_stroke");
  // straight_cut's stroke cuts from frame ~23 to ~121: stop at 80.
  const auto recording = truncated_recording("straight_cut", 80, dir / "rec");
  const auto r = tachi::test::run(run_args(recording.string(), 214, dir / "run"), 150s);
  ASSERT_EQ(r.exit_code, 0) << r.err << logs(dir / "run");
  const auto s = read_json(dir / "run" / "summary.json");
  EXPECT_GT(s["cut_length_m"].get<double>(), 0.1) << s.dump();
  EXPECT_EQ(s["cuts"], 1) << s.dump();
  EXPECT_EQ(s["strokes"], 1) << s.dump();
}

// A simulator killed in the run's last second: the restarted one replays its journal, settles and
// ends the run (not a 20 s timeout), and the summary counts the run's samples and cut.
TEST(TachiRunNumbers, ASimulatorKilledAtTheEndEndsTheRunWithATrueSummary) {
  tachi::test::ScratchDir out("numbers_late_kill");
  ChildProcess run(run_args(kRecordings + "/straight_cut", 215, out.path()));
  // The sensor's last line says the recording was played; the simulator settles 1.5 s after it.
  bool played = false;
  for (int i = 0; i < 1200 && !played && run.running(); ++i) {
    played = read_text(out / "sensor.log").find(" depth frames, hand tracked in ") != std::string::npos;
    if (!played) std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(played) << run.err();
  const std::string pid_text = [&] {
    for (const auto& entry : fs::directory_iterator("/proc")) {
      std::string cmd = read_text(entry.path() / "cmdline");
      std::replace(cmd.begin(), cmd.end(), '\0', ' ');
      if (cmd.find("tachi-sim") != std::string::npos && cmd.find("--domain 215 ") != std::string::npos)
        return entry.path().filename().string();
    }
    return std::string();
  }();
  ASSERT_FALSE(pid_text.empty());
  ::kill(std::stoi(pid_text), SIGKILL);
  ASSERT_EQ(run.wait(120s), 0) << run.err();
  const auto s = read_json(out / "summary.json");
  EXPECT_EQ(s["ended"], "recording played, cloth settled") << s.dump();
  EXPECT_EQ(s["restarts"], 1);
  EXPECT_EQ(s["hand_samples"], s["frames"]) << s.dump();
  EXPECT_EQ(s["cuts"], 1) << s.dump();
}
