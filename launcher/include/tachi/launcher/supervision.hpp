// Supervision policy, kept apart from fork/exec so it is tested without processes: a child that
// dies is restarted after 0.1 s, then after a backoff that doubles (0.5 s, 1 s, 2 s, ... capped at 4 s); one that dies
// `max_deaths` times within `window` stops the run. Exit codes that restarting cannot fix (bad flags,
// no device) stop the run at once.
#pragma once

#include "tachi/common/exit_codes.hpp"

#include <chrono>
#include <deque>
#include <string>

namespace tachi::launcher {

/// How `tachi run` ended: its own exit code (docs/cli.md "tachi run").
enum RunExit : int {
  kRunOk = 0,            ///< the recording was played and the outputs written, or a clean stop by SIGINT/SIGTERM
  kRunFailure = 1,       ///< the launcher itself failed (e.g. cannot write --out)
  kRunUsage = 2,         ///< bad flag or config; or a child rejected its flags
  kRunNoDevice = 3,      ///< no Kinect / no capture device (a child exited 3)
  kRunChildGaveUp = 4,   ///< a child kept dying (max deaths within the window)
  kRunDiskFull = common::kExitDiskFull,  ///< a child ran out of disk space (a child exited 5)
};

class RestartPolicy {
 public:
  using Clock = std::chrono::steady_clock;
  explicit RestartPolicy(int max_deaths = 5, std::chrono::milliseconds window = std::chrono::seconds(30));

  struct Decision {
    bool give_up = false;
    std::chrono::milliseconds delay{0};  ///< wait this long before the restart
  };
  /// A death at `now`: restart after `delay`, or give up.
  Decision on_death(Clock::time_point now);
  [[nodiscard]] int deaths_in_window() const { return static_cast<int>(deaths_.size()); }

 private:
  int max_deaths_;
  std::chrono::milliseconds window_;
  std::deque<Clock::time_point> deaths_;
};

/// What a child's exit means for the run.
enum class ExitMeaning {
  Done,      ///< a finite child finished its work (exit 0)
  Died,      ///< crashed, was killed, or a long-running child ended by itself: restart
  Usage,     ///< exit 2: its flags are wrong; restarting cannot help
  NoDevice,  ///< exit 3: no Kinect / capture device
  DiskFull,  ///< exit 5: no space left for its outputs; a restart would only fail again
};
/// `status` as waitpid() reports it.
[[nodiscard]] ExitMeaning classify_exit(int status, bool finite);
/// "exit code 1", "killed by SIGKILL", ...
[[nodiscard]] std::string describe_exit(int status);

}  // namespace tachi::launcher
