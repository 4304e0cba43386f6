// The bus across processes: two real executables exchange keyed samples and 200 KB cloth
// states at 60 Hz with none lost, and a late-joining process receives the last topology.
#include "paths.hpp"
#include "process.hpp"

#include <gtest/gtest.h>

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
