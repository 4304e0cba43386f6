#include "tachi/launcher/supervision.hpp"

#include <gtest/gtest.h>

#include <csignal>

using namespace std::chrono_literals;
using namespace tachi::launcher;

TEST(RestartPolicy, BacksOffThenGivesUpAtTheFifthDeathWithinTheWindow) {
  RestartPolicy policy;  // 5 deaths in 30 s
  const auto t0 = RestartPolicy::Clock::time_point{} + 1000s;
  std::vector<std::chrono::milliseconds> delays;
  for (int i = 0; i < 4; ++i) {
    const auto d = policy.on_death(t0 + i * 1s);
    ASSERT_FALSE(d.give_up) << i;
    delays.push_back(d.delay);
  }
  EXPECT_EQ(delays, (std::vector<std::chrono::milliseconds>{100ms, 500ms, 1000ms, 2000ms}));
  EXPECT_TRUE(policy.on_death(t0 + 5s).give_up);
}

TEST(RestartPolicy, DeathsOutsideTheWindowAreForgotten) {
  RestartPolicy policy(5, 30s);
  const auto t0 = RestartPolicy::Clock::time_point{} + 1000s;
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(policy.on_death(t0 + i * 10s).give_up) << i;  // one every 10 s: 3 in a window
  EXPECT_LE(policy.deaths_in_window(), 4);
}

namespace {
int exited(int code) { return (code & 0xff) << 8; }  // the status waitpid reports for exit(code)
int killed(int signo) { return signo & 0x7f; }
}  // namespace

TEST(ExitMeaning, FiniteChildrenFinishOthersDie) {
  EXPECT_EQ(classify_exit(exited(0), true), ExitMeaning::Done);
  EXPECT_EQ(classify_exit(exited(0), false), ExitMeaning::Died);  // a filter must not end by itself
  EXPECT_EQ(classify_exit(exited(1), true), ExitMeaning::Died);
  EXPECT_EQ(classify_exit(killed(SIGKILL), true), ExitMeaning::Died);
  EXPECT_EQ(classify_exit(exited(2), false), ExitMeaning::Usage);
  EXPECT_EQ(classify_exit(exited(3), true), ExitMeaning::NoDevice);
  EXPECT_EQ(classify_exit(exited(tachi::common::kExitDiskFull), false), ExitMeaning::DiskFull);  // restarting cannot free space
  EXPECT_EQ(describe_exit(killed(SIGKILL)), "killed by SIGKILL");
  EXPECT_EQ(describe_exit(exited(4)), "exit code 4");
}
