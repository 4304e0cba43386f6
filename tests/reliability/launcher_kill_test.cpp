// No lost cuts under the launcher (docs/reliability.md): `tachi run` on the recorded straight
// cut, once undisturbed and once per node with that node SIGKILLed mid-stroke (in two waves of runs). The launcher
// restarts it and the restarted node picks up where the killed one stopped: the sensor after the
// last frame it published (--resume), the filter from its journal under the same session, the
// simulator from its journal, the viewer from the transient-local topology. Each run must complete
// with the undisturbed run's cut: the same strokes and pieces, the cut line from the same entry to the
// same exit (within a cell: two live runs differ by a frame in where the gate opens on the swaying
// cloth). The kill waits for the hand to be cutting, and the test checks that cutting went on after
// it. The same for `tachi run --in-process`, whose one process (tachi-pipeline, every node in it) is
// killed mid-stroke. Domain ids 195-199 and 221 belong to this file.
#include "paths.hpp"
#include "bus_wait.hpp"
#include "process.hpp"
#include "same_cut.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/run_partition.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <future>
#include <fstream>
#include <map>
#include <regex>
#include <thread>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;
using tachi::test::entry_and_exit_columns;
namespace fs = std::filesystem;

namespace {
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

struct RunResult {
  int exit_code = -1;
  nlohmann::json summary;
  std::string log;
  int cutting_before_kill = 0;  ///< stroke samples with the gate cutting that the bus carried before the kill
  int cutting_after_kill = 0;   ///< ... and after it, up to the end of the run
};


// The pid the launcher logged for `program` ("started tachi-sim (pid 1234)"), once it did.
std::optional<pid_t> started_pid(ChildProcess& launcher, const std::string& program, std::chrono::milliseconds timeout) {
  const std::regex started("started " + program + " \\(pid ([0-9]+)\\)");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline && launcher.running()) {
    std::smatch m;
    const std::string err = launcher.err();
    if (std::regex_search(err, m, started)) return static_cast<pid_t>(std::stol(m[1]));
    launcher.wait_for_output("never printed", 20ms);  // reads what the launcher wrote meanwhile
  }
  return std::nullopt;
}

// victim: a node of a multi-process run ("sensor", ...), "pipeline" for an in-process run's one process,
// or none.
RunResult run(unsigned domain, const std::string& victim) {
  tachi::test::ScratchDir out("tachi_kill_" + (victim.empty() ? std::string("none") : victim));
  const bool in_process = victim == "pipeline";
  // The test watches the run's strokes (in the run's partition; read_every_run() was called) to kill
  // on an event, not after a guess.
  tachi::bus::Participant dds{domain};
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes{dds, tachi::bus::topics::stroke};
  std::vector<std::string> args{kBin + "/tachi", "run", "--recording", kRecordings + "/straight_cut", "--grid", "32", "--domain",
                                std::to_string(domain), "--out", out.path().string(), "--headless", "--settle", "1.5",
                                // The grid cut lists the cells it cut (summary cut_line), which the comparison reads.
                                "--set", "sim.cut-mode=grid",
                                // Twice the recorded pace: the stroke still lasts ~1.6 s, and the kill lands after
                                // its first 5 cutting samples (~0.1 s in), which the test checks.
                                "--rate", "2"};
  if (in_process) args.push_back("--in-process");
  ChildProcess launcher(args);
  RunResult r;
  if (!victim.empty()) {
    // The sensor starts last; the hand crosses the cloth between ~0.7 s and ~2 s of the recording at twice its pace.
    const auto sensor = started_pid(launcher, in_process ? "tachi-pipeline" : "tachi-sensor", 20s);
    const auto pid = victim == "sensor" ? sensor : started_pid(launcher, "tachi-" + victim, 1s);
    EXPECT_TRUE(sensor && pid) << launcher.err();
    if (pid) {
      // Mid-stroke: the kill lands once the filter has published a few samples with the gate
      // cutting (the hand is on the cloth), and the test checks afterwards that cutting went on.
      r.cutting_before_kill = tachi::test::wait_for_matching<tachi_msg_StrokeSample>(
          strokes, 5, tachi::test::is_cutting, 30s, [&] { return launcher.running(); });
      ::kill(*pid, SIGKILL);
    }
    while (launcher.running()) r.cutting_after_kill += tachi::test::take_matching<tachi_msg_StrokeSample>(strokes, tachi::test::is_cutting, 100ms);
  }
  r.exit_code = launcher.wait(120s);
  r.log = launcher.err();
  if (victim == "viewer") {
    // The killed viewer's unfinished video is kept aside; the restarted viewer writes the run's video.
    EXPECT_TRUE(fs::exists(out / "video.before-restart-1.mp4")) << r.log;
    EXPECT_TRUE(fs::exists(out / "video.mp4")) << r.log;
  }
  std::ifstream in(out / "summary.json");
  r.summary = in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
  if (!victim.empty())
    for (const char* log : {"sensor.log", "filter.log", "sim.log", "pipeline.log"}) {
      std::ifstream l(out / log);
      r.log += std::string("\n--- ") + log + "\n" + std::string(std::istreambuf_iterator<char>(l), {});
    }
  return r;
}

}  // namespace

TEST(NoLostCutsUnderTheLauncher, EachNodeKilledMidStrokeInTurnLeavesTheUndisturbedCut) {
  // The runs go in two waves, each run on its own domain: a run mostly waits on the recording's real
  // time (the five took ~55 s one after another), and each waits on its own events. Not all five at
  // once: on a loaded machine five pipelines starved each other (a restarted sensor's run once cut nothing).
  tachi::bus::read_every_run();
  const std::vector<std::string> victims{"sensor", "filter", "sim", "viewer", "pipeline"};
  auto undisturbed_run = std::async(std::launch::async, run, 195u, std::string());
  std::vector<std::future<RunResult>> killed_runs;
  for (unsigned i = 0; i < 2; ++i) killed_runs.push_back(std::async(std::launch::async, run, 196u + i, victims[i]));
  const RunResult undisturbed = undisturbed_run.get();
  std::vector<RunResult> killed_results;
  for (auto& f : killed_runs) killed_results.push_back(f.get());
  killed_runs.clear();
  for (unsigned i = 2; i < victims.size(); ++i)
    killed_runs.push_back(std::async(std::launch::async, run, victims[i] == "pipeline" ? 221u : 196u + i, victims[i]));
  for (auto& f : killed_runs) killed_results.push_back(f.get());

  ASSERT_EQ(undisturbed.exit_code, 0) << undisturbed.log;
  ASSERT_TRUE(undisturbed.summary.is_object()) << undisturbed.log;
  const auto [entry, exit] = entry_and_exit_columns(undisturbed.summary["cut_line"]);
  ASSERT_GT(undisturbed.summary["cut_particles"].get<int>(), 0) << undisturbed.log;
  std::printf("undisturbed: %d strokes, %d pieces, %d particles, cut line u %d..%d, %.3f m\n",
              undisturbed.summary["strokes"].get<int>(), undisturbed.summary["pieces"].get<int>(),
              undisturbed.summary["cut_particles"].get<int>(), entry, exit, undisturbed.summary["cut_length_m"].get<double>());

  for (std::size_t i = 0; i < victims.size(); ++i) {
    const std::string& victim = victims[i];
    const RunResult& killed = killed_results[i];
    SCOPED_TRACE("tachi-" + victim + " killed");  // tachi-pipeline: every node of an in-process run at once
    ASSERT_EQ(killed.exit_code, 0) << killed.log;
    ASSERT_TRUE(killed.summary.is_object()) << killed.log;
    // The kill landed inside the stroke: the hand was cutting before it and went on cutting after it.
    EXPECT_GE(killed.cutting_before_kill, 5) << killed.log;
    EXPECT_GT(killed.cutting_after_kill, 0) << killed.log;
    const auto& s = killed.summary;
    const auto [k_entry, k_exit] = entry_and_exit_columns(s["cut_line"]);
    const double recovery_ms = s["recoveries"].empty() ? -1.0 : s["recoveries"][0]["recovery_ms"].get<double>();
    std::printf("%s killed: %d strokes, %d pieces, %d particles, cut line u %d..%d, %.3f m; recovered in %.0f ms\n",
                victim.c_str(), s["strokes"].get<int>(), s["pieces"].get<int>(), s["cut_particles"].get<int>(), k_entry, k_exit,
                s["cut_length_m"].get<double>(), recovery_ms);
    EXPECT_EQ(s["restarts"], 1) << killed.log;
    ASSERT_EQ(s["recoveries"].size(), 1u) << killed.log;
    EXPECT_EQ(s["recoveries"][0]["node"], victim);
    // It came back; how fast is a benchmark's figure (bench/launcher/recovery.py, docs/benchmarks.md),
    // not an assertion that a loaded machine breaks.
    EXPECT_GT(recovery_ms, 0.0) << killed.log;
    // The same cut: no stroke split in two, none lost, none played twice.
    EXPECT_EQ(s["frames"], undisturbed.summary["frames"]) << killed.log;
    EXPECT_EQ(s["strokes"], undisturbed.summary["strokes"]) << killed.log;
    EXPECT_EQ(s["cuts"], undisturbed.summary["cuts"]) << killed.log;
    tachi::test::expect_same_cut(s, undisturbed.summary, killed.log);
  }
}

namespace {
// A process that is gone, or a zombie waiting for init to reap it (it holds nothing any more).
bool gone(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), {});
  if (text.empty()) return true;
  const auto paren = text.rfind(')');
  return paren != std::string::npos && paren + 2 < text.size() && (text[paren + 2] == 'Z' || text[paren + 2] == 'X');
}
}  // namespace

// Children die with the launcher: `tachi run` SIGKILLed mid-run (nothing of it runs to stop its
// children) leaves no node running a second later (the kernel sends each the death signal,
// PR_SET_PDEATHSIG). Domain id 220.
TEST(ChildrenDieWithTheLauncher, NoNodeOutlivesASigkilledLauncherByASecond) {
  tachi::test::ScratchDir out("tachi_launcher_death");
  ChildProcess launcher({kBin + "/tachi", "run", "--recording", kRecordings + "/straight_cut", "--grid", "32", "--domain", "220",
                         "--out", out.path().string(), "--headless"});
  std::vector<std::pair<std::string, pid_t>> nodes;
  // The sensor starts last: once it is logged, all four run.
  for (const std::string node : {"sim", "viewer", "filter", "sensor"}) {
    const auto pid = started_pid(launcher, "tachi-" + node, 30s);
    ASSERT_TRUE(pid) << node << " never started:\n" << launcher.err();
    nodes.emplace_back(node, *pid);
  }
  // Mid-stroke, as in the kill test above: every node busy (the hand crosses between ~1.5 and 3.5 s).
  std::this_thread::sleep_for(2500ms);
  for (const auto& [node, pid] : nodes) ASSERT_FALSE(gone(pid)) << node << " ended before the launcher was killed";
  launcher.signal(SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  std::map<std::string, long> took_ms;
  while (took_ms.size() < nodes.size() && std::chrono::steady_clock::now() - killed < 5s) {
    for (const auto& [node, pid] : nodes)
      if (!took_ms.count(node) && gone(pid))
        took_ms[node] = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - killed).count();
    std::this_thread::sleep_for(5ms);
  }
  for (const auto& [node, pid] : nodes) {
    ASSERT_TRUE(took_ms.count(node)) << "tachi-" << node << " (pid " << pid << ") still runs 5 s after the launcher died";
    std::printf("tachi-%s gone %ld ms after the launcher's SIGKILL\n", node.c_str(), took_ms[node]);
    EXPECT_LT(took_ms[node], 1000) << "tachi-" << node;
  }
  launcher.wait(5s);
}

// A launcher whose log nobody reads: its stderr is a pipe already full when it starts (a harness that reads
// only at the end, `tachi run 2>&1 | less` scrolled back). It used to block on its first log line and stop
// supervising; it must run the recording to its end, write the summary and exit 0, its log lines dropped.
// Domain id 224.
TEST(UnreadLog, ALauncherWhoseStderrIsAFullPipeStillRunsTheRecordingToItsEnd) {
  tachi::test::ScratchDir out("tachi_unread_log");
  const auto fds = tachi::test::full_pipe();

  const std::vector<std::string> args{kBin + "/tachi", "run", "--recording", kRecordings + "/straight_cut", "--grid", "32",
                                      "--domain", "224", "--out", out.path().string(), "--headless", "--rate", "2"};
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);

  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + 90s;
  while (::waitpid(pid, &status, WNOHANG) == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(50ms);
  const bool ended = std::chrono::steady_clock::now() < deadline;
  if (!ended) {
    ::kill(pid, SIGKILL);  // a launcher blocked on its log: unblock the test, then fail it
    ::waitpid(pid, &status, 0);
  }
  ::close(fds[0]);
  ASSERT_TRUE(ended) << "tachi run did not end: blocked on its unread stderr?";
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(summary.is_object());
  EXPECT_EQ(summary["cuts"], 1) << summary.dump();
  EXPECT_EQ(summary["restarts"], 0);
}
