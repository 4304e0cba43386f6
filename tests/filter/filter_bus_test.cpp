// tachi-filter on the bus: raw hands, voice commands and cloth states in, one stroke sample per hand out.
#include "paths.hpp"
#include "node_status.hpp"
#include "process.hpp"
#include "synthetic_hands.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <set>
#include <thread>

namespace {

using namespace std::chrono_literals;

tachi_msg_RawHandSample to_raw(const tachi::filter::HandSample& h) {
  tachi_msg_RawHandSample m{};
  m.sensor_id = 1;
  m.frame = h.frame;
  m.capture_time_ns = h.stamp_ns;
  m.position_m = {h.position_m.x(), h.position_m.y(), h.position_m.z()};
  m.tracked = h.tracked;
  m.confidence = h.confidence;
  return m;
}

struct Bus {
  explicit Bus(unsigned domain)
      : dds(domain), hands(dds, tachi::bus::topics::raw_hand), voice(dds, tachi::bus::topics::voice_command),
        cloth(dds, tachi::bus::topics::cloth_state), strokes(dds, tachi::bus::topics::stroke),
        status(dds, tachi::bus::topics::node_status) {}
  tachi::bus::Participant dds;
  tachi::bus::Writer<tachi_msg_RawHandSample> hands;
  tachi::bus::Writer<tachi_msg_VoiceCommand> voice;
  tachi::bus::Writer<tachi_msg_ClothState> cloth;
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes;
  tachi::bus::Reader<tachi_msg_NodeStatus> status;

  bool connected() {
    return hands.wait_for_readers(1, 10s) && voice.wait_for_readers(1, 10s) && cloth.wait_for_readers(1, 10s) &&
           strokes.wait_for_writers(1, 10s);
  }
  std::vector<tachi_msg_StrokeSample> collect(std::size_t n) {
    std::vector<tachi_msg_StrokeSample> got;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (got.size() < n && std::chrono::steady_clock::now() < deadline) {
      strokes.wait_for_data(100ms);
      for (const auto& s : strokes.take()) got.push_back(*s);
    }
    return got;
  }
};

TEST(FilterBus, PushRecordingBecomesOneStrokeOnTheBus) {
  constexpr unsigned kDomain = 72;
  Bus bus{kDomain};
  tachi::test::ChildProcess filter{{tachi::test::executable("tachi-filter"), "--domain", std::to_string(kDomain)}};
  ASSERT_TRUE(bus.connected()) << "tachi-filter did not join the bus";
  const auto hands = tachi::filter::testing::push_and_back(4);
  for (const auto& h : hands) {
    bus.hands.write(to_raw(h));
    std::this_thread::sleep_for(3ms);  // the raw topic keeps the last 64: pace them like a sensor would
  }
  const auto got = bus.collect(hands.size());
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0) << filter.err();
  ASSERT_GE(got.size(), hands.size() * 9 / 10);
  std::set<std::uint32_t> cutting;
  for (const auto& s : got) {
    if (s.gate == tachi_msg_GATE_CUTTING) {
      cutting.insert(s.stroke_id);
      EXPECT_EQ(s.opened_by, tachi_msg_GATE_SOURCE_THRESHOLD);
    }
  }
  EXPECT_EQ(cutting, std::set<std::uint32_t>{1});
  EXPECT_EQ(got.back().closed_by, tachi_msg_GATE_SOURCE_THRESHOLD);
}

TEST(FilterBus, VoiceCommandsAndClothStateDriveTheGate) {
  constexpr unsigned kDomain = 73;
  Bus bus{kDomain};
  tachi::test::ChildProcess filter{{tachi::test::executable("tachi-filter"), "--domain", std::to_string(kDomain), "--gate", "voice"}};
  ASSERT_TRUE(bus.connected()) << "tachi-filter did not join the bus";

  // A cloth state with one particle bulging to world z = 0.2: a hand at world z = 0.25 is 5 cm from it.
  float xyz[3] = {0.0F, 0.0F, 0.2F};
  tachi_msg_ClothState state{};
  state.positions._buffer = xyz;
  state.positions._length = 3;
  state.positions._maximum = 3;
  state.positions._release = false;
  bus.cloth.write(state);
  // The filter has the cloth (its heartbeat counts the states it accepted).
  ASSERT_TRUE(tachi::test::wait_for_metric(bus.status, "tachi-filter", "cloth_states", 1, 10s)) << filter.err();

  tachi::filter::HandSample h;
  h.tracked = true;
  h.position_m = {0.0F, 0.0F, 1.25F};
  const auto send = [&](int frames) {
    for (int i = 0; i < frames; ++i) {
      h.stamp_ns += 33'333'333;
      ++h.frame;
      bus.hands.write(to_raw(h));
      std::this_thread::sleep_for(5ms);
    }
  };
  int said = 0;
  const auto say = [&](tachi_msg_VoiceCommandKind kind) {
    tachi_msg_VoiceCommand c{};
    c.command = kind;
    std::snprintf(c.phrase, sizeof c.phrase, "%s", kind == tachi_msg_VOICE_START ? "start cutting" : "stop cutting");
    bus.voice.write(c);
    // Applied before the next hand sample is sent (the filter's heartbeat counts the commands it applied).
    ASSERT_TRUE(tachi::test::wait_for_metric(bus.status, "tachi-filter", "voice_commands", ++said, 10s)) << filter.err();
  };
  send(5);
  say(tachi_msg_VOICE_START);
  send(5);
  say(tachi_msg_VOICE_STOP);
  send(5);
  const auto got = bus.collect(15);
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0) << filter.err();
  ASSERT_EQ(got.size(), 15U);
  for (int i = 0; i < 15; ++i) {
    const bool cutting = i >= 5 && i < 10;
    EXPECT_EQ(got[static_cast<std::size_t>(i)].gate, cutting ? tachi_msg_GATE_CUTTING : tachi_msg_GATE_IDLE) << i;
    EXPECT_NEAR(got[static_cast<std::size_t>(i)].distance_to_cloth_m, 0.05F, 1e-3F) << i;
  }
  EXPECT_EQ(got[7].opened_by, tachi_msg_GATE_SOURCE_VOICE);
  EXPECT_EQ(got[12].closed_by, tachi_msg_GATE_SOURCE_VOICE);
  EXPECT_EQ(got[12].stroke_id, 1U);
}

}  // namespace
