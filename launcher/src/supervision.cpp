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
  // 500 ms << (n - 1): quick for a one-off crash, slower for a child that keeps failing.
  const auto delay = std::chrono::milliseconds(500) * (1 << std::min(n - 1, 3));
  return {false, delay};
}

ExitMeaning classify_exit(int status, bool finite) {
  if (WIFEXITED(status)) {
    const int code = WEXITSTATUS(status);
    if (code == 0 && finite) return ExitMeaning::Done;
    if (code == 2) return ExitMeaning::Usage;
    if (code == 3) return ExitMeaning::NoDevice;
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
