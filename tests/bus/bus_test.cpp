// The typed bus in one process: keyed samples, large zero-copy samples, transient-local
// late joiners, waitset timeouts, shared domains, and errors that name the failing call.
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

using namespace std::chrono_literals;
namespace bus = tachi::bus;

namespace {
// Domain ids 10-19 belong to this file (docs/testing.md; 16-19 are set in their tests).
constexpr std::uint32_t kKeyedDomain = 10;
constexpr std::uint32_t kLargeDomain = 11;
constexpr std::uint32_t kLateJoinerDomain = 12;
constexpr std::uint32_t kErrorDomain = 13;
constexpr std::uint32_t kWaitSetDomain = 14;
constexpr std::uint32_t kSharedDomain = 15;
}  // namespace

TEST(Bus, KeyedSamplesArriveInOrderPerKey) {
  bus::Participant dds{kKeyedDomain};
  bus::Writer<tachi_msg_StrokeSample> writer{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_StrokeSample> reader{dds, bus::topics::stroke};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  for (std::uint64_t frame = 0; frame < 50; ++frame)
    for (std::uint32_t key = 1; key <= 3; ++key) {
      tachi_msg_StrokeSample s{};
      s.sensor_id = key;
      s.frame = frame;
      writer.write(s);
    }
  std::map<std::uint32_t, std::vector<std::uint64_t>> frames;
  std::size_t total = 0;
  for (int tries = 0; tries < 100 && total < 150; ++tries) {
    reader.wait_for_data(50ms);
    for (const auto& s : reader.take()) {
      frames[s->sensor_id].push_back(s->frame);
      ++total;
    }
  }
  ASSERT_EQ(total, 150u);
  ASSERT_EQ(frames.size(), 3u);
  for (const auto& [key, list] : frames) {
    ASSERT_EQ(list.size(), 50u) << "key " << key;
    for (std::size_t i = 0; i < list.size(); ++i) EXPECT_EQ(list[i], i) << "key " << key;
  }
}

TEST(Bus, LargeSampleWrittenWithoutCopyArrivesIntact) {
  bus::Participant dds{kLargeDomain};
  bus::Writer<tachi_msg_ClothState> writer{dds, bus::topics::cloth_state};
  bus::Reader<tachi_msg_ClothState> reader{dds, bus::topics::cloth_state};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  std::vector<float> positions(50'000);  // 200 KB
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = static_cast<float>(i) * 0.5f;
  tachi_msg_ClothState state{};
  state.cloth_id = 1;
  state.frame = 9;
  state.positions._buffer = positions.data();
  state.positions._length = state.positions._maximum = static_cast<std::uint32_t>(positions.size());
  state.positions._release = false;
  writer.write(state);
  ASSERT_TRUE(reader.wait_for_data(5s));
  const auto got = reader.take();
  ASSERT_EQ(got.size(), 1u);
  ASSERT_EQ(got[0]->positions._length, positions.size());
  EXPECT_EQ(got[0]->frame, 9u);
  EXPECT_EQ(got[0]->positions._buffer[0], 0.0f);
  EXPECT_EQ(got[0]->positions._buffer[49'999], 49'999 * 0.5f);
  EXPECT_NE(got[0]->positions._buffer, positions.data()) << "the received sample owns its own buffer";
}

TEST(Bus, LateReaderReceivesOnlyTheLastTopologyPerCloth) {
  bus::Participant dds{kLateJoinerDomain};
  bus::Writer<tachi_msg_ClothTopology> writer{dds, bus::topics::cloth_topology};
  for (std::uint32_t cloth : {1u, 2u})
    for (std::uint32_t version = 1; version <= 4; ++version) {
      tachi_msg_ClothTopology t{};
      t.cloth_id = cloth;
      t.version = version * cloth;
      writer.write(t);
    }
  bus::Participant late{kLateJoinerDomain};
  bus::Reader<tachi_msg_ClothTopology> reader{late, bus::topics::cloth_topology};
  std::map<std::uint32_t, std::vector<std::uint32_t>> versions;
  for (int tries = 0; tries < 40 && versions.size() < 2; ++tries) {
    reader.wait_for_data(50ms);
    for (const auto& t : reader.take()) versions[t->cloth_id].push_back(t->version);
  }
  EXPECT_EQ(versions[1], std::vector<std::uint32_t>{4});
  EXPECT_EQ(versions[2], std::vector<std::uint32_t>{8});
}

TEST(Bus, WaitSetTimesOutWithoutDataAndWakesWithIt) {
  bus::Participant dds{kWaitSetDomain};
  bus::Reader<tachi_msg_VoiceCommand> voice{dds, bus::topics::voice_command};
  bus::Reader<tachi_msg_RawHandSample> hands{dds, bus::topics::raw_hand};
  bus::WaitSet waitset{dds};
  waitset.attach(voice);
  waitset.attach(hands);
  EXPECT_FALSE(waitset.wait(30ms));
  bus::Writer<tachi_msg_VoiceCommand> writer{dds, bus::topics::voice_command};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  tachi_msg_VoiceCommand command{};
  command.command = tachi_msg_VOICE_STOP;
  std::snprintf(command.phrase, sizeof command.phrase, "%s", "stop cutting");
  writer.write(command);
  EXPECT_TRUE(waitset.wait(5s));
  const auto got = voice.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_STREQ(got[0]->phrase, "stop cutting");
  EXPECT_TRUE(hands.take().empty());
}

TEST(Bus, ParticipantsShareADomainAndOutliveEachOther) {
  auto first = std::make_unique<bus::Participant>(kSharedDomain);
  bus::Participant second{kSharedDomain};
  first.reset();  // must not tear down the domain the second participant uses
  bus::Writer<tachi_msg_NodeStatus> writer{second, bus::topics::node_status};
  bus::Reader<tachi_msg_NodeStatus> reader{second, bus::topics::node_status};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  tachi_msg_NodeStatus status{};
  std::snprintf(status.node, sizeof status.node, "%s", "tachi-test");
  writer.write(status);
  ASSERT_TRUE(reader.wait_for_data(5s));
  EXPECT_EQ(reader.take().size(), 1u);
}

TEST(Bus, BadConfigFailsWithTheCallNamed) {
  const auto path = std::filesystem::temp_directory_path() / "tachi_bad_cyclone_config.xml";
  std::ofstream(path) << "<CycloneDDS><Domain><NoSuchElement>1</NoSuchElement></Domain></CycloneDDS>";
  try {
    bus::Participant dds{kErrorDomain, path.string()};
    FAIL() << "a config Cyclone rejects must throw";
  } catch (const bus::DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("dds_create_domain"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("domain 13"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(bus::Participant(kErrorDomain, "/nonexistent/tachi.xml"), std::runtime_error);
  // The failed attempts leave nothing behind: the domain can still be created normally.
  EXPECT_NO_THROW(bus::Participant{kErrorDomain});
}

TEST(Bus, EmbeddedConfigKeepsTrafficOnLoopback) {
  const std::string xml = bus::kLoopbackConfigXml;
  EXPECT_NE(xml.find(R"(<NetworkInterface name="lo" multicast="false"/>)"), std::string::npos);
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find(R"(<Peer address="127.0.0.1"/>)"), std::string::npos);
}

// `tachi run --lossy`'s config: Cyclone accepts the two documents (it refuses an element it does not
// know, as above). Whether the loss is applied and repaired needs two processes: the launcher's
// TachiRun.ALossyLinkCutsAsTheCleanRunDoes (in one process Cyclone delivers without the network).
TEST(Bus, ALossyConfigIsOneCycloneAccepts) {
  constexpr std::uint32_t kLossyDomain = 18;
  EXPECT_THROW((void)bus::lossy_config_xml(bus::kLoopbackConfigXml, 1000), std::invalid_argument);
  EXPECT_THROW((void)bus::lossy_config_xml(bus::kLoopbackConfigXml, -1), std::invalid_argument);
  const std::string xml = bus::lossy_config_xml(bus::dds_config_xml(""), 500);
  EXPECT_EQ(xml.find(bus::kLoopbackConfigXml), 0u) << "the base config first, whole";
  EXPECT_NE(xml.find("<XmitLossiness>500</XmitLossiness>"), std::string::npos);
  EXPECT_NE(xml.find("<SPDPInterval>500 ms</SPDPInterval>"), std::string::npos) << "a lost announcement is repeated soon";
  const auto path = std::filesystem::temp_directory_path() / "tachi_lossy_cyclone_config.xml";
  std::ofstream(path) << xml;
  EXPECT_NO_THROW(bus::Participant(kLossyDomain, path.string()));
  std::filesystem::remove(path);
}

TEST(Heartbeat, AnnouncesStartStateChangesAndStop) {
  constexpr std::uint32_t kHeartbeatDomain = 16;
  bus::Participant dds{kHeartbeatDomain};
  bus::Reader<tachi_msg_NodeStatus> reader{dds, bus::topics::node_status};
  std::vector<tachi_msg_NodeState> states;
  const auto collect = [&] {
    // Status keeps the last sample per node, so read after each update.
    for (int i = 0; i < 10; ++i) {
      reader.wait_for_data(20ms);
      for (const auto& s : reader.take()) {
        EXPECT_STREQ(s->node, "tachi-test");
        states.push_back(s->state);
      }
    }
  };
  {
    bus::Heartbeat heartbeat{dds, "tachi-test", std::chrono::hours(1)};
    collect();
    heartbeat.update(tachi_msg_NODE_STARTING, 0, 0);  // no change, period not over: not published
    collect();
    heartbeat.update(tachi_msg_NODE_RUNNING, 5, 7, "ok");
    collect();
  }
  collect();
  EXPECT_EQ(states, (std::vector<tachi_msg_NodeState>{tachi_msg_NODE_STARTING, tachi_msg_NODE_RUNNING, tachi_msg_NODE_STOPPING}));
}

TEST(Heartbeat, CarriesHostMetricsAndRejectionsByReason) {
  constexpr std::uint32_t kMetricsDomain = 17;
  bus::Participant dds{kMetricsDomain};
  bus::Reader<tachi_msg_NodeStatus> reader{dds, bus::topics::node_status};
  bus::Heartbeat heartbeat{dds, "tachi-metrics", std::chrono::hours(1)};
  heartbeat.set_metric("frames", 12);
  heartbeat.set_metric("frames", 13);  // replaces, does not add
  heartbeat.count_rejected("nonfinite");
  heartbeat.count_rejected("nonfinite", 2);
  heartbeat.count_rejected("backwards_time");
  heartbeat.update(tachi_msg_NODE_RUNNING, 1, 2);  // state change: published now
  std::map<std::string, double> metrics;
  std::uint64_t rejected = 0;
  std::string host;
  for (int i = 0; i < 50 && metrics.empty(); ++i) {
    reader.wait_for_data(20ms);
    for (const auto& s : reader.take()) {
      if (s->state != tachi_msg_NODE_RUNNING) continue;
      rejected = s->rejected;
      host = s->host;
      for (std::uint32_t k = 0; k < s->metrics._length; ++k) metrics[s->metrics._buffer[k].name] = s->metrics._buffer[k].value;
    }
  }
  EXPECT_EQ(rejected, 4u);
  EXPECT_FALSE(host.empty());
  EXPECT_EQ(metrics.size(), 3u);
  EXPECT_DOUBLE_EQ(metrics["frames"], 13.0);
  EXPECT_DOUBLE_EQ(metrics["rejected.nonfinite"], 3.0);
  EXPECT_DOUBLE_EQ(metrics["rejected.backwards_time"], 1.0);
}

// An observer (the launcher's trace, the bus tools) is not a consumer: a writer waiting for its readers
// (tachi-sensor --wait-readers, for the filter) is not let go by an observer that matched first.
TEST(Bus, AnObserverDoesNotCountAsAWritersReader) {
  constexpr std::uint32_t kObserverDomain = 19;
  bus::Participant dds{kObserverDomain};
  bus::Writer<tachi_msg_RawHandSample> writer{dds, bus::topics::raw_hand};
  bus::Reader<tachi_msg_RawHandSample> trace{dds, bus::topics::raw_hand, bus::ReaderKind::Observer};
  ASSERT_TRUE(trace.wait_for_writers(1, 5s)) << "the observer matched the writer";
  dds_publication_matched_status_t status{};
  ASSERT_EQ(dds_get_publication_matched_status(writer.handle(), &status), DDS_RETCODE_OK);
  EXPECT_EQ(status.current_count, 1u) << "DDS matched it";
  EXPECT_EQ(writer.matched_readers(), 0u);
  EXPECT_FALSE(writer.wait_for_readers(1, 200ms));
  bus::Reader<tachi_msg_RawHandSample> filter{dds, bus::topics::raw_hand};
  EXPECT_TRUE(writer.wait_for_readers(1, 5s));
  EXPECT_EQ(writer.matched_readers(), 1u);
}

// A reader deserializes into its own chunk of receive buffers, reused by every take: samples of changing
// size, taken with room for one or for 256, arrive whole, and a buffer that held a disposal notice's key
// is filled again correctly.
TEST(Bus, AReadersReceiveBuffersAreReusedAcrossTakes) {
  constexpr std::uint32_t kReuseDomain = 24;  // docs/testing.md: lent from bus_multiprocess_test's range
  bus::Participant dds{kReuseDomain};
  bus::Writer<tachi_msg_ClothState> writer{dds, bus::topics::cloth_state};
  bus::Reader<tachi_msg_ClothState> reader{dds, bus::topics::cloth_state};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  const auto sample_size = [](std::uint64_t frame) -> std::size_t { return frame % 3 == 0 ? 30'000 : 1 + frame % 7; };
  const auto write = [&](std::uint64_t frame) {
    std::vector<float> positions(sample_size(frame));
    for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = static_cast<float>(frame * 100'000 + i);
    tachi_msg_ClothState state{};
    state.cloth_id = 1;
    state.frame = frame;
    state.positions._buffer = positions.data();
    state.positions._length = state.positions._maximum = static_cast<std::uint32_t>(positions.size());
    state.positions._release = false;
    writer.write(state);
  };
  // One at a time: the state profile keeps only the newest two, and each take fills the same first buffer.
  for (std::uint64_t frame = 0; frame < 30; ++frame) {
    write(frame);
    std::vector<bus::Owned<tachi_msg_ClothState>> got;
    for (int tries = 0; tries < 250 && got.empty(); ++tries) {
      reader.wait_for_data(20ms);
      got = reader.take(frame % 2 == 0 ? 1 : 256);
    }
    ASSERT_EQ(got.size(), 1u) << "frame " << frame;
    const auto& s = got[0];
    ASSERT_EQ(s->frame, frame);
    ASSERT_EQ(s->positions._length, sample_size(frame)) << "frame " << frame;
    for (std::size_t i = 0; i < s->positions._length; ++i)
      ASSERT_EQ(s->positions._buffer[i], static_cast<float>(frame * 100'000 + i)) << "frame " << frame;
  }

  // Disposal notices (a writer that goes away) land in the buffers too, and are dropped by take.
  bus::Reader<tachi_msg_NodeStatus> statuses{dds, bus::topics::node_status};
  std::vector<std::string> nodes;
  const auto collect = [&] {
    for (int i = 0; i < 10; ++i) {
      statuses.wait_for_data(20ms);
      for (const auto& s : statuses.take()) nodes.emplace_back(s->node);
    }
  };
  { bus::Heartbeat first{dds, "tachi-first", std::chrono::hours(1)}; collect(); }
  collect();
  { bus::Heartbeat second{dds, "tachi-second-node", std::chrono::hours(1)}; collect(); }
  collect();
  EXPECT_EQ(nodes, (std::vector<std::string>{"tachi-first", "tachi-first", "tachi-second-node", "tachi-second-node"}));
}

// A reader that joins late receives the writer's kept history (strokes: the newest 256 per hand) even when
// another reader acknowledged every sample first: Cyclone prunes what all readers acknowledged down to the
// durability service's depth (default 1), which once left a late simulator one stroke sample of many.
TEST(Bus, ALateReaderReceivesTheKeptHistoryThatAnotherReaderAcknowledged) {
  constexpr std::uint32_t kKeptHistoryDomain = 25;  // docs/testing.md: lent from bus_multiprocess_test's range
  bus::Participant dds{kKeptHistoryDomain};
  bus::Writer<tachi_msg_StrokeSample> writer{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_StrokeSample> early{dds, bus::topics::stroke};
  ASSERT_TRUE(writer.wait_for_readers(1, 5s));
  constexpr std::uint64_t kWritten = 200;  // within both the early reader's and the writer's 256
  for (std::uint64_t frame = 0; frame < kWritten; ++frame) {
    tachi_msg_StrokeSample s{};
    s.sensor_id = 1;
    s.frame = frame;
    writer.write(s);
  }
  std::size_t early_got = 0;
  for (int tries = 0; tries < 200 && early_got < kWritten; ++tries) {
    early.wait_for_data(20ms);
    early_got += early.take().size();
  }
  ASSERT_EQ(early_got, kWritten);
  ASSERT_EQ(dds_wait_for_acks(writer.handle(), DDS_SECS(5)), DDS_RETCODE_OK);

  bus::Participant late_dds{kKeptHistoryDomain};
  bus::Reader<tachi_msg_StrokeSample> late{late_dds, bus::topics::stroke};
  std::vector<std::uint64_t> frames;
  for (int tries = 0; tries < 100 && frames.size() < kWritten; ++tries) {
    late.wait_for_data(20ms);
    for (const auto& s : late.take()) frames.push_back(s->frame);
  }
  ASSERT_EQ(frames.size(), kWritten);
  for (std::uint64_t i = 0; i < kWritten; ++i) EXPECT_EQ(frames[i], i);
}
