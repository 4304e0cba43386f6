// No lost cuts (docs/reliability.md): the recorded straight cut through sensor, filter and simulator,
// once undisturbed and once with the simulator killed (SIGKILL) mid-stroke and started again on its
// journal. The restarted simulator replays the journal, catches up on the strokes it
// missed (transient-local history), and ends with the same cut: the same pieces, the same cut line
// from edge to edge. Then the same with the filter killed: the stroke is ended cleanly and the
// restarted filter's strokes are new strokes, never the old one's continuation.
#include "paths.hpp"
#include "bus_wait.hpp"
#include "process.hpp"
#include "same_cut.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>
#include <future>
#include <optional>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;
using tachi::test::entry_and_exit_columns;

namespace {
// Domain ids 190-194 belong to this file (docs/testing.md).
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

std::vector<std::string> sim_args(unsigned domain, const std::filesystem::path& journal, const std::filesystem::path& out) {
  // Grid cuts: their summary lists the cut line cell by cell, which the comparison below reads.
  return {kBin + "/tachi-sim", "--grid", "32", "--pin", "top-edge", "--cut-mode", "grid", "--domain", std::to_string(domain),
          "--exit-when-idle", "2", "--journal", journal.string(), "--export", out.string()};
}

nlohmann::json read_summary(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json{};
}

struct PipelineRun {
  nlohmann::json summary;
  std::string logs;
  double recovery_ms = -1;
  int cutting_before_kill = 0;  ///< stroke samples with the gate cutting before the kill
  int cutting_after_kill = 0;   ///< ... and after it, while the sensor played on
};


enum class Kill { None, Sim, Filter };

PipelineRun run_pipeline(unsigned domain, Kill kill) {
  tachi::test::ScratchDir dir{"nolost"};
  const std::string d = std::to_string(domain);
  PipelineRun r;
  tachi::bus::Participant dds{domain};
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes{dds, tachi::bus::topics::stroke};
  auto sim = std::make_unique<ChildProcess>(sim_args(domain, dir / "sim.journal", dir / "out"));
  auto filter = std::make_unique<ChildProcess>(std::vector<std::string>{kBin + "/tachi-filter", "--domain", d, "--gate", "threshold"});
  ChildProcess sensor({kBin + "/tachi-sensor", "--recording", kRecordings + "/straight_cut", "--rate", "1", "--domain", d,
                       "--wait-readers", "1"});
  if (kill != Kill::None) {
    // Mid-stroke: kill once the filter has published a few samples with the gate cutting; the test
    // checks below that cutting went on after the kill.
    r.cutting_before_kill = tachi::test::wait_for_matching<tachi_msg_StrokeSample>(
        strokes, 5, tachi::test::is_cutting, 30s, [&] { return sensor.running(); });
    auto& victim = kill == Kill::Sim ? sim : filter;
    victim->signal(SIGKILL);
    victim->wait(5s);
    r.logs += "killed: " + victim->err() + "\n";
    const auto t0 = std::chrono::steady_clock::now();
    if (kill == Kill::Sim) {
      sim = std::make_unique<ChildProcess>(sim_args(domain, dir / "sim.journal", dir / "out"));
      // Recovered: the journal is replayed and the cloth published again.
      while (sim->running() && sim->err().find("replayed") == std::string::npos &&
             std::chrono::steady_clock::now() - t0 < 10s) {
        sim->wait_for_output("never printed", 20ms);
      }
    } else {
      filter = std::make_unique<ChildProcess>(std::vector<std::string>{kBin + "/tachi-filter", "--domain", d, "--gate", "threshold"});
    }
    r.recovery_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    while (sensor.running()) r.cutting_after_kill += tachi::test::take_matching<tachi_msg_StrokeSample>(strokes, tachi::test::is_cutting, 100ms);
    EXPECT_GE(r.cutting_before_kill, 5) << "the kill did not land inside the stroke";
    EXPECT_GT(r.cutting_after_kill, 0) << "the stroke had ended before the kill";
  }
  EXPECT_EQ(sensor.wait(60s), 0) << sensor.err();
  EXPECT_EQ(sim->wait(60s), 0) << sim->err();
  filter->signal(SIGINT);
  EXPECT_EQ(filter->wait(10s), 0) << filter->err();
  r.logs += "sim: " + sim->err() + "\nfilter: " + filter->err();
  r.summary = read_summary(dir / "out");
  return r;
}

}  // namespace

TEST(NoLostCuts, ASimulatorKilledMidStrokeRecoversTheSameCut) {
  // Side by side on their own domains: each mostly waits on the recording's clock and on its own events.
  auto undisturbed_run = std::async(std::launch::async, run_pipeline, 190u, Kill::None);
  const PipelineRun killed = run_pipeline(191, Kill::Sim);
  const PipelineRun undisturbed = undisturbed_run.get();
  ASSERT_TRUE(undisturbed.summary.is_object()) << undisturbed.logs;
  ASSERT_TRUE(killed.summary.is_object()) << killed.logs;
  const auto [entry, exit] = entry_and_exit_columns(undisturbed.summary["cut_line"]);
  const auto [k_entry, k_exit] = entry_and_exit_columns(killed.summary["cut_line"]);
  std::printf("undisturbed: %d particles, cut line u %d..%d; killed: %d particles, u %d..%d; recovery %.0f ms\n",
              undisturbed.summary["cut_particles"].get<int>(), entry, exit, killed.summary["cut_particles"].get<int>(), k_entry,
              k_exit, killed.recovery_ms);
  EXPECT_NE(killed.logs.find("replayed"), std::string::npos) << killed.logs;
  EXPECT_GT(killed.recovery_ms, 0.0) << killed.logs;  // it came back (how fast: bench/launcher/recovery.py)
  tachi::test::expect_same_cut(killed.summary, undisturbed.summary, killed.logs);
}

TEST(NoLostCuts, AFilterKilledMidStrokeEndsTheStrokeCleanly) {
  const PipelineRun killed = run_pipeline(192, Kill::Filter);
  ASSERT_TRUE(killed.summary.is_object()) << killed.logs;
  EXPECT_GT(killed.summary["cut_particles"].get<int>(), 0) << killed.logs;
  // The old filter's stroke 1 was closed when the new filter's session appeared, and the new
  // filter's strokes are reported as strokes of their own: no stroke id ever spans two filters.
  EXPECT_NE(killed.logs.find("stroke 1 cut"), std::string::npos) << killed.logs;
  EXPECT_EQ(killed.summary["pieces"], 1) << killed.logs;
}
