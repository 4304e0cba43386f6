#include "tachi/common/log_sink.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <limits.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>

namespace tachi::common {

bool NonBlockingFdSink::write_now(const std::string& text) {
  // POLLOUT on a pipe means at least a page (PIPE_BUF) is free, and a write() of at most PIPE_BUF bytes then goes
  // out whole without waiting (POSIX atomicity); sink_it_ keeps every line within that. A regular file is always
  // ready. A partial write (a file system filling up) is a failure: the rest is not waited for.
  pollfd p{fd_, POLLOUT, 0};
  if (::poll(&p, 1, 0) != 1 || (p.revents & POLLOUT) == 0) return false;
  for (;;) {
    const ssize_t n = ::write(fd_, text.data(), text.size());
    if (n < 0 && errno == EINTR) continue;
    return n == static_cast<ssize_t>(text.size());
  }
}

void NonBlockingFdSink::sink_it_(const spdlog::details::log_msg& msg) {
  spdlog::memory_buf_t formatted;
  formatter_->format(msg, formatted);
  std::string text;
  if (dropped_since_ > 0) {
    text += '[';
    text += std::to_string(dropped_since_);
    text += " log lines dropped: the output could not take them (unread, or full)]\n";
  }
  text.append(formatted.data(), formatted.size());
  // A line longer than a pipe's atomic write would be written in parts, and a blocking write() waits for the
  // reader between them: such a line (a dumped message, a long path list) is cut to fit, and says so.
  static constexpr char kCut[] = " [line cut: longer than PIPE_BUF]\n";
  if (text.size() > PIPE_BUF) {
    text.resize(PIPE_BUF - (sizeof kCut - 1));
    text += kCut;
  }
  if (write_now(text)) {
    dropped_since_ = 0;
  } else {
    ++dropped_since_;
    ++dropped_total_;
  }
}

std::shared_ptr<spdlog::logger> stderr_logger(const std::string& name) {
  if (::isatty(STDERR_FILENO)) return spdlog::stderr_color_mt(name);
  auto logger = std::make_shared<spdlog::logger>(name, std::make_shared<NonBlockingFdSink>(STDERR_FILENO));
  spdlog::register_logger(logger);
  return logger;
}

}  // namespace tachi::common
