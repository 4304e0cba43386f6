// A log nobody reads never stops the process writing it (common/log_sink.hpp).
#include "process.hpp"
#include "tachi/common/log_sink.hpp"

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <future>
#include <string>

using namespace std::chrono_literals;

namespace {
// Reads what the pipe holds, without waiting for more.
std::string drain(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  std::string out;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) out.append(buffer, static_cast<std::size_t>(n));
  ::fcntl(fd, F_SETFL, flags);
  return out;
}
}  // namespace

TEST(NonBlockingFdSink, AFullPipeDropsAndCountsLinesInsteadOfBlockingAndSaysSoOnceItDrains) {
  const auto fds = tachi::test::full_pipe();

  auto sink = std::make_shared<tachi::common::NonBlockingFdSink>(fds[1]);
  spdlog::logger logger("test", sink);
  logger.set_pattern("%v");
  // On a blocking sink this call would wait for a reader for ever; it must return at once.
  auto logged = std::async(std::launch::async, [&] {
    logger.info("status line 1");
    logger.info("status line 2");
  });
  const bool returned = logged.wait_for(5s) == std::future_status::ready;
  if (!returned) drain(fds[0]);  // unblock it, so the test ends and reports
  logged.wait();
  ASSERT_TRUE(returned) << "logging blocked on a full pipe";
  EXPECT_EQ(sink->dropped(), 2u);

  // The reader comes back: the next line goes out, after a line that says how many were lost.
  const std::string backlog = drain(fds[0]);
  EXPECT_EQ(backlog.find("status line"), std::string::npos) << "the dropped lines were not written";
  logger.info("status line 3");
  const std::string out = drain(fds[0]);
  EXPECT_EQ(out, "[2 log lines dropped: the output could not take them (unread, or full)]\nstatus line 3\n");
  EXPECT_EQ(sink->dropped(), 2u);
  ::close(fds[0]);
  ::close(fds[1]);
}
