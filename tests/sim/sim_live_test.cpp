// tachi-sim in live mode as a process: strokes in over DDS, topology, cut events and a summary out.
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/bus/topology_assembler.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <set>
#include <fstream>
#include <limits>
#include <thread>

using namespace std::chrono_literals;
namespace bus = tachi::bus;

namespace {
// Domain ids 30-39 belong to this file (docs/testing.md).
constexpr unsigned kDomain = 30;

tachi_msg_StrokeSample sample(std::uint32_t stroke, std::uint64_t frame, float x, float y, bool cutting) {
  tachi_msg_StrokeSample s{};
  s.sensor_id = 1;
  s.stroke_id = stroke;
  s.frame = frame;
  s.time_ns = static_cast<std::int64_t>(frame) * 16'666'667;
  s.position_m = {x, y, 0.0f};
  s.tracked = true;
  s.gate = cutting ? tachi_msg_GATE_CUTTING : tachi_msg_GATE_IDLE;
  return s;
}
}  // namespace

TEST(SimLive, CutsOffTheLowerPieceFromStrokesOverDdsAndReportsIt) {
  const tachi::test::ScratchDir scratch{"sim_live"};
  const auto out = scratch / "out";
  tachi::test::ChildProcess sim({tachi::test::executable("tachi-sim"), "--cut-mode", "exact", "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain),
                                 "--exit-when-idle", "1.5", "--export", out.string()});
  bus::Participant dds{kDomain};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  bus::Reader<tachi_msg_ClothTopologyDelta> deltas{dds, bus::topics::cloth_topology_delta};
  ASSERT_TRUE(strokes.wait_for_readers(1, 20s)) << sim.err();
  ASSERT_TRUE(deltas.wait_for_writers(1, 20s)) << sim.err();
  ASSERT_TRUE(topologies.wait_for_data(10s)) << "the initial topology is published (transient-local)";
  const auto initial = topologies.take();
  ASSERT_FALSE(initial.empty());
  EXPECT_EQ(initial.back()->particle_grid._length, 16u * 16u);
  EXPECT_EQ(initial.back()->base_version, initial.back()->version) << "a first publication has no change list";

  std::uint64_t frame = 0;
  // A faulty peer's sample must be rejected, not crash the simulator or cut.
  auto bad = sample(1, frame++, std::numeric_limits<float>::quiet_NaN(), 0.0f, true);
  strokes.write(bad);
  for (int i = 0; i <= 40; ++i) {
    strokes.write(sample(1, frame++, -0.7f + 1.4f * static_cast<float>(i) / 40.0f, -0.1f, true));
    std::this_thread::sleep_for(5ms);
  }
  strokes.write(sample(1, frame++, 0.7f, -0.1f, false));

  std::vector<std::uint32_t> pieces, fallen;
  for (int i = 0; i < 100 && pieces.empty(); ++i) {
    cuts.wait_for_data(50ms);
    for (const auto& cut : cuts.take()) {
      EXPECT_EQ(cut->stroke_id, 1u);
      EXPECT_GT(cut->cut_line._length, 1u);  // exact mode: the grid points nearest the cut's path
      pieces.push_back(cut->pieces);
      fallen.push_back(cut->fallen_pieces);
    }
  }
  ASSERT_EQ(pieces, std::vector<std::uint32_t>{2});
  EXPECT_EQ(fallen, std::vector<std::uint32_t>{1});
  ASSERT_EQ(sim.wait(30s), 0) << sim.err();
  std::ifstream summary_file(out / "summary.json");
  ASSERT_TRUE(summary_file) << sim.err();
  const auto summary = nlohmann::json::parse(summary_file);
  EXPECT_EQ(summary["pieces"], 2);
  EXPECT_EQ(summary["fallen_pieces"], 1);
  EXPECT_EQ(summary["hand_samples_rejected"], 1);
  EXPECT_TRUE(std::filesystem::exists(out / "cloth.obj"));
  EXPECT_TRUE(std::filesystem::exists(out / "pattern.svg"));
  EXPECT_EQ(summary["cut_mode"], "exact");

  // The deltas (<= 30 Hz) applied to the first keyframe give exactly the last keyframe.
  bus::TopologyAssembler assembled;
  ASSERT_TRUE(assembled.on_keyframe(*initial.back()));
  std::size_t delta_count = 0;
  for (const auto& d : deltas.take(1024)) {
    EXPECT_TRUE(assembled.on_delta(*d)) << "delta " << d->base_version << " -> " << d->version;
    ++delta_count;
  }
  EXPECT_GT(delta_count, 0u);
  EXPECT_LE(summary["topology_updates"].get<std::size_t>(), 1u + summary["steps"].get<std::size_t>() / 2)
      << "at most one delta every other 60 Hz step";
  const auto keyframes = topologies.take();
  ASSERT_FALSE(keyframes.empty()) << "a keyframe after the cuts";
  const auto& last = *keyframes.back();
  EXPECT_EQ(assembled.version(), last.version);
  EXPECT_EQ(assembled.particle_count(), last.particle_grid._length);
  std::set<std::array<std::uint32_t, 3>> from_deltas(assembled.triangles().begin(), assembled.triangles().end());
  std::set<std::array<std::uint32_t, 3>> from_keyframe;
  for (std::uint32_t i = 0; i + 2 < last.triangles._length; i += 3) {
    from_keyframe.insert({last.triangles._buffer[i], last.triangles._buffer[i + 1], last.triangles._buffer[i + 2]});
  }
  EXPECT_EQ(from_deltas, from_keyframe);
  EXPECT_LT(summary["topology_bytes_per_update"].get<double>(), summary["topology_keyframe_bytes"].get<double>());
}

TEST(SimLive, StopsCleanlyOnSigint) {
  tachi::test::ChildProcess sim({tachi::test::executable("tachi-sim"), "--grid", "8", "--domain", std::to_string(kDomain + 1)});
  // In its loop: it publishes the cloth.
  tachi::bus::Participant dds{kDomain + 1};
  tachi::bus::Reader<tachi_msg_ClothState> states{dds, tachi::bus::topics::cloth_state};
  ASSERT_TRUE(states.wait_for_data(20s)) << sim.err();
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0) << sim.err();
}

TEST(SimLive, ARunDoesNotEndWhileARestartedHandSourceIsStarting) {
  // The launcher restarts a killed sensor, which replays its recording before it publishes again (1-2 s under
  // load): with --exit-when-idle 0.5 the simulator ended in that gap and the run lost the rest of its stroke.
  const unsigned domain = kDomain + 2;
  tachi::test::ChildProcess sim({tachi::test::executable("tachi-sim"), "--grid", "8", "--domain", std::to_string(domain),
                                 "--exit-when-idle", "0.5"});
  bus::Participant dds{domain};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  ASSERT_TRUE(strokes.wait_for_readers(1, 20s)) << sim.err();
  // The restarted sensor: its heartbeat says STARTING from the moment it is up (given a second to be discovered).
  tachi::bus::Heartbeat restarted_sensor{dds, "tachi-sensor"};
  std::this_thread::sleep_for(1s);
  for (std::uint64_t frame = 0; frame < 5; ++frame) strokes.write(sample(1, frame, 0.0f, 2.0f, false));
  ASSERT_TRUE(strokes.wait_for_acks(5s));
  std::this_thread::sleep_for(2s);
  EXPECT_TRUE(sim.running()) << "ended while the sensor was starting: " << sim.err();
  restarted_sensor.update(tachi_msg_NODE_RUNNING, 0, 0);
  EXPECT_EQ(sim.wait(10s), 0) << "settles and ends once the sensor runs and stays silent: " << sim.err();
}

TEST(SimLive, RejectsAStrokeFileOutsideOfflineMode) {
  const auto result = tachi::test::run({tachi::test::executable("tachi-sim"), "--stroke", "/dev/null"}, 10s);
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("--stroke"), std::string::npos) << result.err;
}
