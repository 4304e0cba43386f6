#include "tachi/common/log_sink.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <poll.h>
#include <unistd.h>

#include <cerrno>

namespace tachi::common {

bool NonBlockingFdSink::write_now(const std::string& text) {
  // POLLOUT on a pipe means a whole page is free, so a line shorter than that goes out in one write() that
  // does not wait (PIPE_BUF atomicity); a regular file is always ready.
  pollfd p{fd_, POLLOUT, 0};
  if (::poll(&p, 1, 0) != 1 || (p.revents & POLLOUT) == 0) return false;
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    written += static_cast<std::size_t>(n);
  }
  return true;
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
