// tachi-sim in live mode as a process: strokes in over DDS, topology, cut events and a summary out.
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
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
  tachi::test::ChildProcess sim({TACHI_SIM_EXE, "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain),
                                 "--exit-when-idle", "1.5", "--export", out.string()});
  bus::Participant dds{kDomain};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  ASSERT_TRUE(strokes.wait_for_readers(1, 20s)) << sim.err();
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
      EXPECT_GT(cut->cut_line._length, 10u);
      pieces.push_back(cut->pieces);
      fallen.push_back(cut->fallen_pieces);
    }
  }
  ASSERT_EQ(pieces, std::vector<std::uint32_t>{2});
  EXPECT_EQ(fallen, std::vector<std::uint32_t>{1});
  std::uint32_t latest_version = 0, duplicated = 0;
  std::uint32_t previous = initial.back()->version;
  for (const auto& t : topologies.take()) {
    // Keep-last-1 may overwrite a publication before it is taken: the change list starts at or after
    // the last version this reader saw, and the message always carries the full topology too.
    EXPECT_GE(t->base_version, previous);
    EXPECT_LT(t->base_version, t->version);
    previous = t->version;
    latest_version = std::max(latest_version, t->version);
    duplicated += t->duplicated_from._length;
  }
  EXPECT_GT(latest_version, initial.back()->version);
  EXPECT_GT(duplicated, 0u) << "the topology update carries its change list";

  ASSERT_EQ(sim.wait(30s), 0) << sim.err();
  std::ifstream summary_file(out / "summary.json");
  ASSERT_TRUE(summary_file) << sim.err();
  const auto summary = nlohmann::json::parse(summary_file);
  EXPECT_EQ(summary["pieces"], 2);
  EXPECT_EQ(summary["fallen_pieces"], 1);
  EXPECT_EQ(summary["hand_samples_rejected"], 1);
  EXPECT_TRUE(std::filesystem::exists(out / "cloth.obj"));
}

TEST(SimLive, StopsCleanlyOnSigint) {
  tachi::test::ChildProcess sim({TACHI_SIM_EXE, "--grid", "8", "--domain", std::to_string(kDomain + 1)});
  std::this_thread::sleep_for(1s);
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0) << sim.err();
}

TEST(SimLive, RejectsAStrokeFileOutsideOfflineMode) {
  const auto result = tachi::test::run({TACHI_SIM_EXE, "--stroke", "/dev/null"}, 10s);
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("--stroke"), std::string::npos) << result.err;
}
