#include "tachi/launcher/supervision.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <cstring>

namespace tachi::launcher {

RestartPolicy::RestartPolicy(int max_deaths, std::chrono::milliseconds window) : max_deaths_(max_deaths), window_(window) {}

RestartPolicy::Decision RestartPolicy::on_death(Clock::time_point now) {
  deaths_.push_back(now);
  while (!deaths_.empty() && now - deaths_.front() > window_) deaths_.pop_front();
  const int n = static_cast<int>(deaths_.size());
  if (n >= max_deaths_) return {true, {}};
  // A one-off crash is restarted at once (100 ms, as systemd's RestartSec): the node picks up where it
  // stopped and the run is back within a second (docs/reliability.md). One that keeps failing backs
  // off: 500 ms << (n - 2), capped at 4 s.
  const auto delay = n == 1 ? std::chrono::milliseconds(100) : std::chrono::milliseconds(500) * (1 << std::min(n - 2, 3));
  return {false, delay};
}

ExitMeaning classify_exit(int status, bool finite) {
  if (WIFEXITED(status)) {
    const int code = WEXITSTATUS(status);
    if (code == 0 && finite) return ExitMeaning::Done;
    if (code == common::kExitUsage) return ExitMeaning::Usage;
    if (code == common::kExitNoDevice) return ExitMeaning::NoDevice;
    if (code == common::kExitDiskFull) return ExitMeaning::DiskFull;
  }
  return ExitMeaning::Died;
}

std::string describe_exit(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const char* name = sigabbrev_np(WTERMSIG(status));
    return std::string("killed by ") + (name ? std::string("SIG") + name : "signal " + std::to_string(WTERMSIG(status)));
  }
  return "status " + std::to_string(status);
}

}  // namespace tachi::launcher
