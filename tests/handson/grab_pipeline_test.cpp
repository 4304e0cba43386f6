// Grabbing by hand through the processes: tachi-filter and tachi-sim on one DDS domain; the
// test plays the sensor (raw hand samples in the camera frame) and the voice (commands on the bus).
// Voice "grab", the hand moves, voice "release": the cloth moved with the hand, and let go.
#include "paths.hpp"
#include "node_status.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/filter/workspace.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
#include <fstream>
#include <thread>

namespace {

using namespace std::chrono_literals;
constexpr unsigned kDomain = 200;  // 200-219 belong to tests/handson (docs/testing.md)

struct Bus {
  Bus() : dds(kDomain), hands(dds, tachi::bus::topics::raw_hand), voice(dds, tachi::bus::topics::voice_command),
          states(dds, tachi::bus::topics::cloth_state), strokes(dds, tachi::bus::topics::stroke),
          status(dds, tachi::bus::topics::node_status) {}
  tachi::bus::Participant dds;
  tachi::bus::Writer<tachi_msg_RawHandSample> hands;
  tachi::bus::Writer<tachi_msg_VoiceCommand> voice;
  tachi::bus::Reader<tachi_msg_ClothState> states;
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes;
  tachi::bus::Reader<tachi_msg_NodeStatus> status;
};

struct State {
  std::int32_t held = -1;
  std::vector<float> xyz;
};

TEST(GrabPipeline, VoiceGrabTheHandMovesVoiceReleaseTheClothMovedWithTheHand) {
  Bus bus;
  tachi::test::ChildProcess sim({tachi::test::executable("tachi-sim"), "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain),
                                 "--duration", "30"});
  tachi::test::ChildProcess filter({tachi::test::executable("tachi-filter"), "--domain", std::to_string(kDomain), "--gate", "threshold"});
  ASSERT_TRUE(bus.hands.wait_for_readers(1, 20s)) << filter.err();
  ASSERT_TRUE(bus.voice.wait_for_readers(1, 20s)) << filter.err();
  ASSERT_TRUE(bus.states.wait_for_writers(1, 20s)) << sim.err();

  const tachi::filter::WorkspaceMapping mapping = tachi::filter::default_mapping();
  // The hand 7 cm in front of grid point (7, 10) of the 1 m cloth: within grab reach (10 cm), not near
  // enough for the threshold gate to start a cut (5 cm).
  const Eigen::Vector3f p0{-0.5F + 7.0F / 15.0F, 0.5F - 10.0F / 15.0F, 0.07F};
  const Eigen::Vector3f p1 = p0 + Eigen::Vector3f{0.15F, 0.10F, 0.0F};
  std::uint64_t frame = 0;
  std::vector<State> seen;
  auto drain = [&] {
    for (const auto& s : bus.states.take()) seen.push_back({s->held_particle, {s->positions._buffer, s->positions._buffer + s->positions._length}});
  };
  auto hand_at = [&](const Eigen::Vector3f& world) {
    tachi_msg_RawHandSample m{};
    m.sensor_id = 1;
    m.frame = frame++;
    m.capture_time_ns = static_cast<std::int64_t>(frame) * 33'333'333;
    const Eigen::Vector3f c = mapping.to_camera(world);
    m.position_m = {c.x(), c.y(), c.z()};
    m.tracked = true;
    m.confidence = 1.0F;
    bus.hands.write(m);
    std::this_thread::sleep_for(33ms);
    drain();
  };
  int said = 0;
  auto say = [&](tachi_msg_VoiceCommandKind kind, const char* phrase) {
    tachi_msg_VoiceCommand c{};
    c.source_id = 1;
    c.command = kind;
    std::snprintf(c.phrase, sizeof c.phrase, "%s", phrase);
    bus.voice.write(c);
    // Applied before the next hand sample (the filter's heartbeat counts the commands it applied).
    ASSERT_TRUE(tachi::test::wait_for_metric(bus.status, "tachi-filter", "voice_commands", ++said, 10s)) << filter.err();
  };

  for (int i = 0; i < 30; ++i) hand_at(p0);
  ASSERT_FALSE(seen.empty()) << sim.err();
  EXPECT_EQ(seen.back().held, -1) << "nothing held before the grab";
  say(tachi_msg_VOICE_GRAB, "grab cloth");
  for (int i = 0; i < 10; ++i) hand_at(p0);
  for (int i = 1; i <= 30; ++i) hand_at(p0 + (p1 - p0) * (static_cast<float>(i) / 30.0F));
  for (int i = 0; i < 20; ++i) hand_at(p1);
  ASSERT_FALSE(seen.empty());
  const State before_release = seen.back();
  int grabbing = 0;
  for (const auto& st : bus.strokes.take()) grabbing += st->gate == tachi_msg_GATE_GRABBING ? 1 : 0;
  EXPECT_GT(grabbing, 30) << "the filter publishes GATE_GRABBING samples after the voice grab";
  if (before_release.held < 0) {  // stop them so that their logs are complete below
    sim.signal(SIGINT);
    filter.signal(SIGINT);
    sim.wait(10s);
    filter.wait(10s);
  }
  ASSERT_GE(before_release.held, 0) << "the hand holds a particle\n" << sim.err() << filter.err();
  const auto held = static_cast<std::size_t>(before_release.held);
  ASSERT_LT(3 * held + 2, before_release.xyz.size());
  const Eigen::Vector3f at{before_release.xyz[3 * held], before_release.xyz[3 * held + 1], before_release.xyz[3 * held + 2]};
  EXPECT_LT((at - p1).norm(), 0.01F) << "the held particle is at the (smoothed) hand";
  // Where that particle was before the grab: the cloth moved with the hand.
  const State& first = seen.front();
  const Eigen::Vector3f was{first.xyz[3 * held], first.xyz[3 * held + 1], first.xyz[3 * held + 2]};
  EXPECT_GT((at - was).norm(), 0.12F);

  say(tachi_msg_VOICE_RELEASE, "release cloth");
  for (int i = 0; i < 30; ++i) hand_at(p1);
  EXPECT_EQ(seen.back().held, -1) << "released";
  const Eigen::Vector3f after{seen.back().xyz[3 * held], seen.back().xyz[3 * held + 1], seen.back().xyz[3 * held + 2]};
  EXPECT_GT((after - at).norm(), 0.01F) << "let go, it swings back under gravity";

  sim.signal(SIGINT);
  filter.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0) << sim.err();
  EXPECT_EQ(filter.wait(10s), 0) << filter.err();
  EXPECT_EQ(sim.err().find("grab refused"), std::string::npos) << sim.err();
}

TEST(ObjectTopic, TheSimulatorPublishesItsObjectForLateViewers) {
  constexpr unsigned kObjectDomain = 201;
  const tachi::test::ScratchDir dir{"object_topic"};
  {
    std::ofstream ply{dir / "line.ply"};
    ply << "ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (int i = 0; i < 10; ++i) ply << 0.1 * i << " 0 0\n";
  }
  tachi::test::ChildProcess sim({tachi::test::executable("tachi-sim"), "--grid", "8", "--domain", std::to_string(kObjectDomain), "--duration", "20",
                                 "--object", (dir / "line.ply").string(), "--object-pose", "0,-0.7,0.2"});
  tachi::bus::Participant dds{kObjectDomain};
  tachi::bus::Reader<tachi_msg_ClothState> states{dds, tachi::bus::topics::cloth_state};
  ASSERT_TRUE(states.wait_for_writers(1, 20s)) << sim.err();
  // The simulator is stepping (a state came), so it published the object before this reader joins.
  ASSERT_TRUE(states.wait_for_data(10s)) << sim.err();
  // A viewer that joins after the publication still gets it (transient-local).
  tachi::bus::Reader<tachi_msg_SceneObject> objects{dds, tachi::bus::topics::scene_object};
  ASSERT_TRUE(objects.wait_for_data(10s)) << sim.err();
  const auto got = objects.take();
  ASSERT_FALSE(got.empty());
  const auto& msg = *got.back();
  ASSERT_EQ(msg.points._length, 30u);
  EXPECT_NEAR(msg.points._buffer[27], 0.9F, 1e-5F);
  EXPECT_NEAR(msg.points._buffer[28], -0.7F, 1e-5F);
  EXPECT_NEAR(msg.points._buffer[29], 0.2F, 1e-5F);
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0) << sim.err();
}

}  // namespace
