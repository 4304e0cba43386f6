// A log that never stops the process writing it. A supervisor whose stderr is a pipe nobody reads (a
// harness reading only at the end, `tachi run 2>&1 | less` scrolled back) blocked in write() once the pipe's
// 64 KiB filled, and stopped supervising: no restarts, no bus polled (it happened to `tachi run` in a soak,
// 26 minutes in). This sink writes a line only when the file descriptor can take it at once (poll, no wait);
// otherwise the line is dropped and counted, and the next line that goes out says how many were lost.
#pragma once

#include <spdlog/logger.h>
#include <spdlog/sinks/base_sink.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace tachi::common {

class NonBlockingFdSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  explicit NonBlockingFdSink(int fd) : fd_(fd) {}
  /// Lines dropped because the descriptor could not take them (total since start; read it while no thread logs).
  [[nodiscard]] std::uint64_t dropped() const { return dropped_total_; }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override;
  void flush_() override {}

 private:
  /// Writes all of `text` if the descriptor takes it without waiting; false (nothing or a part written) if not.
  bool write_now(const std::string& text);
  int fd_;
  std::uint64_t dropped_since_ = 0;  // since the last line that went out
  std::uint64_t dropped_total_ = 0;
};

/// The default logger for program `name` on stderr: colours on a terminal (it is read as it is written),
/// NonBlockingFdSink on anything else (a pipe, a file, a socket).
[[nodiscard]] std::shared_ptr<spdlog::logger> stderr_logger(const std::string& name);

}  // namespace tachi::common
