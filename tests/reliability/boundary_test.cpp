// Validation at the bus boundary through the real executables (docs/reliability.md): a faulty or
// hostile peer's samples are refused and counted by reason in the node's heartbeat, and a flood at
// ten times the sensor's rate leaves the filter's memory bounded.
#include "paths.hpp"
#include "process.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <fstream>
#include <limits>
#include <map>
#include <thread>

using namespace std::chrono_literals;
namespace bus = tachi::bus;
using tachi::test::ChildProcess;

namespace {
// Domain ids 185-189 belong to this file (docs/testing.md).
const std::string kBin = tachi::test::bin_dir();

// The newest "rejected.*" metrics `node` published, waiting until `reason` shows up (or 10 s pass).
std::map<std::string, double> rejections(bus::Reader<tachi_msg_NodeStatus>& status, const std::string& node,
                                         const std::string& reason) {
  std::map<std::string, double> found;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (found.count(reason) == 0 && std::chrono::steady_clock::now() < deadline) {
    status.wait_for_data(100ms);
    for (const auto& s : status.take()) {
      if (node != s->node) continue;
      for (std::uint32_t k = 0; k < s->metrics._length; ++k) {
        const std::string name = s->metrics._buffer[k].name;
        if (name.rfind("rejected.", 0) == 0) found[name.substr(9)] = s->metrics._buffer[k].value;
      }
    }
  }
  return found;
}

tachi_msg_RawHandSample hand(std::uint64_t frame, std::int64_t t_ns, float x) {
  tachi_msg_RawHandSample h{};
  h.sensor_id = 5;
  h.frame = frame;
  h.capture_time_ns = t_ns;
  h.position_m = {x, 0.0F, 1.2F};
  h.tracked = true;
  h.confidence = 1.0F;
  return h;
}

std::size_t resident_kb(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  std::size_t kb = 0;
  while (status >> key) {
    if (key == "VmRSS:") {
      status >> kb;
      return kb;
    }
  }
  return 0;
}

int pid_of(bus::Reader<tachi_msg_NodeStatus>& status, const std::string& node) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    status.wait_for_data(100ms);
    for (const auto& s : status.take())
      if (node == s->node) return static_cast<int>(s->pid);
  }
  return -1;
}
}  // namespace

TEST(Boundary, TheFilterRefusesAndCountsBadHandSamples) {
  ChildProcess filter({kBin + "/tachi-filter", "--domain", "186"});
  bus::Participant dds{186};
  bus::Writer<tachi_msg_RawHandSample> hands{dds, bus::topics::raw_hand};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  bus::Reader<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  ASSERT_TRUE(hands.wait_for_readers(1, 20s)) << filter.err();
  // Raw hands are keep-last 64: paced like a sensor, so a burst does not overwrite unread samples.
  for (const auto& h : {hand(0, 1'000'000'000, 0.1F), hand(1, 1'033'000'000, std::numeric_limits<float>::quiet_NaN()),
                        hand(2, 1'066'000'000, 1e30F),
                        hand(3, 950'000'000, 0.2F),  // 50 ms before the last good sample
                        hand(4, 1'100'000'000, 0.3F)}) {
    hands.write(h);
    std::this_thread::sleep_for(30ms);
  }
  const auto counted = rejections(status, "tachi-filter", "time_backwards");
  EXPECT_EQ(counted.count("nonfinite") ? counted.at("nonfinite") : 0, 1.0) << filter.err();
  EXPECT_EQ(counted.count("out_of_range") ? counted.at("out_of_range") : 0, 1.0);
  EXPECT_EQ(counted.count("time_backwards") ? counted.at("time_backwards") : 0, 1.0);
  // Only the two good samples became strokes, and nothing non-finite went on.
  int out = 0;
  for (int i = 0; i < 20 && out < 2; ++i) {
    strokes.wait_for_data(100ms);
    for (const auto& s : strokes.take()) {
      ++out;
      EXPECT_TRUE(std::isfinite(s->position_m.x)) << s->frame;
    }
  }
  EXPECT_EQ(out, 2);
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0);
}

TEST(Boundary, TheSimulatorRefusesAndCountsBadStrokeSamples) {
  ChildProcess sim({kBin + "/tachi-sim", "--domain", "189", "--grid", "16"});
  bus::Participant dds{189};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(strokes.wait_for_readers(1, 20s)) << sim.err();
  const auto stroke = [](std::uint32_t id, std::int64_t t_ns, float x) {
    tachi_msg_StrokeSample s{};
    s.sensor_id = 2;
    s.session_id = 42;
    s.stroke_id = id;
    s.time_ns = t_ns;
    s.position_m = {x, 0.0F, 0.0F};
    s.tracked = true;
    s.gate = tachi_msg_GATE_IDLE;
    return s;
  };
  strokes.write(stroke(3, 1'000'000'000, 0.1F));
  strokes.write(stroke(3, 1'010'000'000, std::numeric_limits<float>::infinity()));
  strokes.write(stroke(3, 900'000'000, 0.1F));    // back in time
  strokes.write(stroke(2, 1'020'000'000, 0.1F));  // a stroke that already ended
  strokes.write(stroke(4, 1'030'000'000, 0.1F));
  const auto counted = rejections(status, "tachi-sim", "stale_id");
  EXPECT_EQ(counted.count("nonfinite") ? counted.at("nonfinite") : 0, 1.0) << "an infinite sample is named for what it is\n" << sim.err();
  EXPECT_EQ(counted.count("out_of_range"), 0u);
  EXPECT_EQ(counted.count("time_backwards") ? counted.at("time_backwards") : 0, 1.0);
  EXPECT_EQ(counted.count("stale_id") ? counted.at("stale_id") : 0, 1.0);
  sim.signal(SIGTERM);
  EXPECT_EQ(sim.wait(10s), 0);
}

// The filter used to trust cloth states (the viewer refused them). A NaN, a 1e30 m and a ragged
// state are refused and counted under their reasons.
TEST(Boundary, TheFilterRefusesAndCountsBadClothStates) {
  ChildProcess filter({kBin + "/tachi-filter", "--domain", "184"});
  bus::Participant dds{184};
  bus::Writer<tachi_msg_ClothState> states{dds, bus::topics::cloth_state};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(states.wait_for_readers(1, 20s)) << filter.err();
  // One state at a time, each until its refusal shows in the heartbeat: the filter looks at the newest
  // state of a tick only, so a burst would hide the bad ones.
  std::map<std::string, double> counted;
  const auto send = [&](std::vector<float> positions, const std::string& reason) {
    tachi_msg_ClothState s{};
    s.cloth_id = 1;
    s.positions._buffer = positions.data();
    s.positions._length = s.positions._maximum = static_cast<std::uint32_t>(positions.size());
    states.write(s);
    counted = rejections(status, "tachi-filter", reason);
  };
  // A piece cut off an hour ago has fallen ~70 km at its terminal speed: a real state, accepted (the
  // out_of_range count below stays 1). Given time to be looked at before the next state hides it.
  {
    std::vector<float> fallen{0.0F, 0.0F, 0.0F, 0.1F, -7.0e4F, 0.0F};
    tachi_msg_ClothState s{};
    s.cloth_id = 1;
    s.positions._buffer = fallen.data();
    s.positions._length = s.positions._maximum = static_cast<std::uint32_t>(fallen.size());
    states.write(s);
    std::this_thread::sleep_for(500ms);
  }
  send({0.0F, 0.0F, std::numeric_limits<float>::quiet_NaN(), 0.1F, 0.0F, 0.0F}, "nonfinite");
  send({0.0F, 0.0F, 1e30F, 0.1F, 0.0F, 0.0F}, "out_of_range");
  send({0.0F, 0.0F, 0.0F, 0.1F}, "oversized");  // not xyz triples
  // A million well-formed particles (12 MB): more than the largest live grid, cut twice over, can be.
  send(std::vector<float>(3'000'000, 0.1F), "oversized");
  // A heartbeat may still carry the first count: wait for the second.
  for (const auto until = std::chrono::steady_clock::now() + 10s;
       counted["oversized"] < 2.0 && std::chrono::steady_clock::now() < until;)
    counted = rejections(status, "tachi-filter", "oversized");
  EXPECT_EQ(counted.count("nonfinite") ? counted.at("nonfinite") : 0, 1.0) << filter.err();
  EXPECT_EQ(counted.count("out_of_range") ? counted.at("out_of_range") : 0, 1.0);
  EXPECT_EQ(counted.count("oversized") ? counted.at("oversized") : 0, 2.0);
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0);
}

// One stroke sample stamped INT64_MAX under the live session's id used to make the
// simulator refuse every later sample of that session as time_backwards (0 cuts). Now it is refused
// as time_ahead, and the stroke right after it cuts the cloth as it would without it.
TEST(Boundary, AFarFutureStrokeSampleLeavesTheNextStrokeCutting) {
  ChildProcess sim({kBin + "/tachi-sim", "--domain", "185", "--grid", "16", "--cut-mode", "exact", "--pin", "top-edge"});
  bus::Participant dds{185};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(strokes.wait_for_readers(1, 20s)) << sim.err();
  ASSERT_TRUE(cuts.wait_for_writers(1, 20s)) << sim.err();
  std::uint64_t frame = 0;
  const auto stroke = [&frame](std::uint32_t id, std::int64_t t_ns, float x, bool cutting) {
    tachi_msg_StrokeSample s{};
    s.sensor_id = 2;
    s.session_id = 0x5e55;
    s.stroke_id = id;
    s.frame = frame++;
    s.time_ns = t_ns;
    s.position_m = {x, -0.1F, 0.0F};
    s.tracked = true;
    s.gate = cutting ? tachi_msg_GATE_CUTTING : tachi_msg_GATE_IDLE;
    return s;
  };
  constexpr std::int64_t kFrame_ns = 16'666'667;
  strokes.write(stroke(1, kFrame_ns, -0.9F, false));
  strokes.write(stroke(1, 2 * kFrame_ns, -0.9F, false));
  strokes.write(stroke(1, std::numeric_limits<std::int64_t>::max(), -0.9F, false));  // the poison
  for (int i = 0; i <= 40; ++i) {
    strokes.write(stroke(1, (3 + i) * kFrame_ns, -0.7F + 1.4F * static_cast<float>(i) / 40.0F, true));
    std::this_thread::sleep_for(5ms);
  }
  strokes.write(stroke(1, 44 * kFrame_ns, 0.7F, false));
  std::vector<std::uint32_t> pieces;
  for (int i = 0; i < 100 && pieces.empty(); ++i) {
    cuts.wait_for_data(50ms);
    for (const auto& cut : cuts.take()) pieces.push_back(cut->pieces);
  }
  EXPECT_EQ(pieces, std::vector<std::uint32_t>{2}) << "the stroke after the poison cut the cloth in two\n" << sim.err();
  const auto counted = rejections(status, "tachi-sim", "time_ahead");
  EXPECT_EQ(counted.count("time_ahead") ? counted.at("time_ahead") : 0, 1.0) << sim.err();
  EXPECT_EQ(counted.count("time_backwards"), 0u) << "nothing after the poison was refused";
  sim.signal(SIGTERM);
  EXPECT_EQ(sim.wait(10s), 0);
}

TEST(Boundary, TheViewerRefusesAnInconsistentTopology) {
  ChildProcess viewer({kBin + "/tachi-viewer", "--headless", "--domain", "187", "--fps", "10"});
  bus::Participant dds{187};
  bus::Writer<tachi_msg_ClothTopology> topology{dds, bus::topics::cloth_topology};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(topology.wait_for_readers(1, 20s)) << viewer.err();
  std::vector<std::uint32_t> triangles{0, 1, 2, 1, 3, 999};  // particle 999 of 4
  std::vector<tachi_msg_GridCoord> grid{{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  std::vector<std::uint8_t> pinned(4, 0);
  tachi_msg_ClothTopology t{};
  t.cloth_id = 1;
  t.version = 1000;
  t.columns = t.rows = 2;
  t.triangles = {static_cast<std::uint32_t>(triangles.size()), static_cast<std::uint32_t>(triangles.size()), triangles.data(), false};
  t.particle_grid = {4, 4, grid.data(), false};
  t.pinned = {4, 4, reinterpret_cast<bool*>(pinned.data()), false};
  topology.write(t);
  const auto counted = rejections(status, "tachi-viewer", "inconsistent_topology");
  EXPECT_EQ(counted.count("inconsistent_topology") ? counted.at("inconsistent_topology") : 0, 1.0) << viewer.err();
  viewer.signal(SIGTERM);
  EXPECT_EQ(viewer.wait(10s), 0);
}

// 300 hand samples a second (ten times a Kinect's 30) for 4 s, from 200 made-up sensors: the
// filter's resident memory grows by less than 20 MB.
TEST(Boundary, AFloodAtTenTimesTheRateKeepsTheFiltersMemoryBounded) {
  ChildProcess filter({kBin + "/tachi-filter", "--domain", "188"});
  bus::Participant dds{188};
  bus::Writer<tachi_msg_RawHandSample> hands{dds, bus::topics::raw_hand};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(hands.wait_for_readers(1, 20s)) << filter.err();
  const int pid = pid_of(status, "tachi-filter");
  ASSERT_GT(pid, 0);
  for (int i = 0; i < 60; ++i) hands.write(hand(static_cast<std::uint64_t>(i), i * 3'333'333LL, 0.1F));
  std::this_thread::sleep_for(500ms);
  const std::size_t before = resident_kb(pid);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 1200; ++i) {
    auto h = hand(static_cast<std::uint64_t>(i), 1'000'000'000LL + i * 3'333'333LL, 0.001F * static_cast<float>(i % 100));
    h.sensor_id = static_cast<std::uint32_t>(i % 200);
    hands.write(h);
    std::this_thread::sleep_until(start + i * 3333us);
  }
  std::this_thread::sleep_for(500ms);
  const std::size_t after = resident_kb(pid);
  std::printf("filter resident memory: %zu kB before, %zu kB after the flood\n", before, after);
  EXPECT_LT(after, before + 20'000);
  const auto counted = rejections(status, "tachi-filter", "too_many_sources");
  EXPECT_GT(counted.count("too_many_sources") ? counted.at("too_many_sources") : 0, 0.0);
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0);
}
