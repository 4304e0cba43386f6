#include "tachi/launcher/child.hpp"
#include "tachi/launcher/supervision.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <thread>

using namespace std::chrono_literals;
using namespace tachi::launcher;

namespace {
int wait_exit(Child& child) {
  for (int i = 0; i < 500; ++i) {
    if (const auto status = child.poll()) return *status;
    std::this_thread::sleep_for(10ms);
  }
  return -1;
}
}  // namespace

TEST(Child, LogsOutputAndReportsHowItEnded) {
  tachi::test::ScratchDir dir("child");
  Child child({"shell", "sh", {"-c", "echo one; echo two >&2; exit 5"}, false}, "/bin/sh", dir / "shell.log");
  child.start();
  const int status = wait_exit(child);
  EXPECT_EQ(describe_exit(status), "exit code 5");
  EXPECT_FALSE(child.running());
  const auto tail = child.last_log_lines(2);
  EXPECT_NE(tail.find("one"), std::string::npos) << tail;
  EXPECT_NE(tail.find("two"), std::string::npos) << tail;
  // A restart appends to the same log.
  child.start();
  wait_exit(child);
  EXPECT_NE(child.last_log_lines(10).find("=== /bin/sh"), std::string::npos);
}

TEST(Child, SignalStopsIt) {
  tachi::test::ScratchDir dir("child");
  Child child({"sleeper", "sleep", {"30"}, false}, "/bin/sleep", dir / "sleep.log");
  child.start();
  child.signal(SIGKILL);
  EXPECT_EQ(describe_exit(wait_exit(child)), "killed by SIGKILL");
}

TEST(Child, MissingProgramIsAnErrorNamingIt) {
  tachi::test::ScratchDir dir("child");
  Child child({"x", "tachi-nothing", {}, false}, dir / "tachi-nothing", dir / "x.log");
  try {
    child.start();
    FAIL() << "started a missing program";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tachi-nothing"), std::string::npos);
  }
}
