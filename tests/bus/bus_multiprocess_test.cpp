// The bus across processes: two real executables exchange keyed samples and 200 KB cloth
// states at 60 Hz with none lost, and a late-joining process receives the last topology.
#include "paths.hpp"
#include "process.hpp"

#include "tachi/bus/topics.hpp"

#include <dds/ddsi/ddsi_serdata_default.h>
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <thread>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

namespace {
// Domain ids 20-29 belong to this file (docs/testing.md).
const std::string kPeer = tachi::test::executable("bus_peer");

std::vector<std::string> peer(const std::string& role, unsigned domain, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{kPeer, role, "--domain", std::to_string(domain)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}
}  // namespace

TEST(BusMultiProcess, KeyedSamplesAt60HzNoneLost) {
  ChildProcess sub(peer("strokes-sub", 20, {"--keys", "4", "--count", "120", "--timeout", "30"}));
  ChildProcess pub(peer("strokes-pub", 20, {"--keys", "4", "--count", "120", "--rate", "60"}));
  EXPECT_EQ(pub.wait(40s), 0) << pub.out() << pub.err();
  ASSERT_EQ(sub.wait(40s), 0) << sub.out() << sub.err();
  EXPECT_NE(sub.out().find(R"("received":480)"), std::string::npos) << sub.out();
}

// 200 KB cloth states (a 128 x 128 cloth) at 60 Hz, fragmented by Cyclone: every one taken intact and in
// order, the newest always there. The State profile keeps the last 2, so a reader starved of CPU for
// more than 33 ms skips stale states by design: at most 5 % (a quiet machine skips none).
TEST(BusMultiProcess, LargeSamplesAt60HzArriveIntactInOrderWithTheNewest) {
  ChildProcess sub(peer("states-sub", 21, {"--count", "120", "--bytes", "200000", "--timeout", "30"}));
  ChildProcess pub(peer("states-pub", 21, {"--count", "120", "--bytes", "200000", "--rate", "60"}));
  EXPECT_EQ(pub.wait(40s), 0) << pub.out() << pub.err();
  ASSERT_EQ(sub.wait(40s), 0) << sub.out() << sub.err();
  EXPECT_NE(sub.out().find(R"("corrupt":0)"), std::string::npos) << sub.out();
  EXPECT_NE(sub.out().find(R"("newest_arrived":true)"), std::string::npos) << sub.out();
}

TEST(BusMultiProcess, LateJoinerReceivesTheLastTopology) {
  ChildProcess pub(peer("topology-pub", 22, {"--linger", "20"}));
  // Join only after the publisher has written all versions.
  ASSERT_TRUE(pub.wait_for_output("published", 20s)) << pub.err();
  const auto late = tachi::test::run(peer("topology-sub", 22, {"--timeout", "20"}), 30s);
  pub.signal(SIGTERM);
  EXPECT_EQ(pub.wait(10s), 0) << pub.err();
  ASSERT_EQ(late.exit_code, 0) << late.out << late.err;
  EXPECT_NE(late.out.find(R"("versions":[3])"), std::string::npos) << late.out;
}

// A writer's samples are sized to themselves. Cyclone 0.10.2's dds_write serializes into the last freed
// sample buffer of the domain's pool, a received one too, and grows one that is too small by 4 KiB; a
// transient-local writer's history keeps it (in tachi-filter, heaptrack: 754 KB of its 977 KB heap peak
// from strokes written into 60-byte raw hand buffers; docs/benchmarks.md, "Soak"). Here 3000 strokes come
// from another process (80 bytes of CDR each) and are taken, which frees their buffers into the pool,
// then 512 statuses of ~100 bytes are written: a reader on the writer's own topic gets the written
// buffers themselves (a local reader of the same type shares them), and none may be larger than 256 bytes.
TEST(BusMultiProcess, AWrittenSampleIsSizedToItselfNotToAReceivedBuffer) {
  namespace bus = tachi::bus;
  bus::Participant dds(23);
  bus::Reader<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  constexpr bus::TopicSpec<tachi_msg_NodeStatus> kKept{"tachi/test/kept_status", bus::QosProfile::Strokes};
  bus::Writer<tachi_msg_NodeStatus> kept{dds, kKept};
  const dds_entity_t written = bus::detail::create_reader(dds, dds_get_topic(kept.handle()), bus::QosProfile::Strokes,
                                                          kKept.name);
  // 600 Hz, not faster: the strokes' readers keep the last 256 samples (QosProfile::Strokes), so a reader that
  // falls behind by more than that loses the oldest, reliable or not. At 3000 Hz a stall of 85 ms under a
  // loaded ctest -j2 did (2999 received, once in a fresh-clone CI run); at 600 Hz it takes 0.43 s.
  ChildProcess pub(peer("strokes-pub", 23, {"--keys", "1", "--count", "3000", "--rate", "600"}));
  unsigned received = 0;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (received < 3000 && std::chrono::steady_clock::now() < deadline) {
    if (!strokes.wait_for_data(200ms)) continue;
    received += static_cast<unsigned>(strokes.take(4096).size());
  }
  EXPECT_EQ(pub.wait(20s), 0) << pub.out() << pub.err();
  ASSERT_EQ(received, 3000u);
  tachi_msg_NodeStatus status{};
  std::strcpy(status.node, "tachi-test");
  std::strcpy(status.host, "localhost");
  std::strcpy(status.detail, "longer than a stroke");  // ~100 bytes of CDR: more than 80, less than 128
  unsigned larger = 0, taken = 0;
  std::array<ddsi_serdata*, 64> samples{};
  std::array<dds_sample_info_t, 64> infos{};
  for (unsigned i = 0; i < 512; ++i) {
    status.messages_in = i;
    kept.write(status);
    const dds_return_t n = dds_takecdr(written, samples.data(), samples.size(), infos.data(), DDS_ANY_STATE);
    ASSERT_GE(n, 0);
    for (dds_return_t k = 0; k < n; ++k) {
      const auto* sample = reinterpret_cast<const ddsi_serdata_default*>(samples[static_cast<std::size_t>(k)]);
      if (sample->size > 256) ++larger;
      ++taken;
      ddsi_serdata_unref(samples[static_cast<std::size_t>(k)]);
    }
  }
  bus::detail::delete_entity(written);
  EXPECT_EQ(taken, 512u);
  EXPECT_EQ(larger, 0u) << larger << " of 512 written samples were kept in a buffer larger than 256 bytes";
}
