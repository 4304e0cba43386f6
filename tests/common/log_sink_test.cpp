// A log nobody reads never stops the process writing it (common/log_sink.hpp).
#include "process.hpp"
#include "tachi/common/log_sink.hpp"

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <limits.h>
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

// A line longer than a pipe's atomic write (4 KiB) with one page free: a plain write() would put out the first
// part and wait for the reader for the rest. The line goes out cut to fit, at once, and says it was cut.
TEST(NonBlockingFdSink, ALineLongerThanAPipePageIsCutToFitInsteadOfWaitingForTheReader) {
  const auto fds = tachi::test::full_pipe();
  std::string page(PIPE_BUF, 'x');
  ASSERT_EQ(::read(fds[0], page.data(), page.size()), static_cast<ssize_t>(page.size()));  // one page free

  auto sink = std::make_shared<tachi::common::NonBlockingFdSink>(fds[1]);
  spdlog::logger logger("test", sink);
  logger.set_pattern("%v");
  const std::string long_line(3 * PIPE_BUF, 'a');
  auto logged = std::async(std::launch::async, [&] { logger.info(long_line); });
  const bool returned = logged.wait_for(5s) == std::future_status::ready;
  std::string out;
  if (!returned) {
    for (int i = 0; i < 20 && logged.wait_for(100ms) != std::future_status::ready; ++i) out += drain(fds[0]);
  }
  logged.wait();
  ASSERT_TRUE(returned) << "logging a long line waited for the reader";
  out = drain(fds[0]);
  const std::size_t at = out.find('a');
  ASSERT_NE(at, std::string::npos) << "the long line was dropped, though a page was free";
  const std::string written = out.substr(at);
  EXPECT_LE(written.size(), static_cast<std::size_t>(PIPE_BUF));
  EXPECT_NE(written.find("[line cut: longer than PIPE_BUF]\n"), std::string::npos) << written.substr(written.size() - 60);
  EXPECT_EQ(sink->dropped(), 0u);
  ::close(fds[0]);
  ::close(fds[1]);
}
