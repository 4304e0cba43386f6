// One supervised child process: started with fork/exec, its stdout and stderr appended to a log
// file (one per node, across restarts), in its own process group so that a terminal's Ctrl-C
// reaches only the launcher, which then stops the children itself, children first. A child whose
// launcher dies gets SIGTERM from the kernel (PR_SET_PDEATHSIG) instead of running on orphaned.
#pragma once

#include "tachi/launcher/config.hpp"

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>

namespace tachi::launcher {

class Child {
 public:
  Child(ChildSpec spec, std::filesystem::path program, std::filesystem::path log);
  ~Child();  // kills a child still running: no process outlives the launcher
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// Starts (or restarts) the process; throws std::runtime_error naming the program on failure.
  void start();
  /// The waitpid() status once the process has exited (reaped once), else nothing.
  std::optional<int> poll();
  void signal(int signo) const;
  [[nodiscard]] bool running() const { return pid_ > 0; }
  [[nodiscard]] pid_t pid() const { return pid_; }
  [[nodiscard]] const ChildSpec& spec() const { return spec_; }
  [[nodiscard]] const std::filesystem::path& log() const { return log_; }
  /// The log's last `n` lines (to say why a child kept dying).
  [[nodiscard]] std::string last_log_lines(int n) const;
  /// The command line, shell-quoted, as the log shows it.
  [[nodiscard]] std::string command_line() const;

 private:
  ChildSpec spec_;
  std::filesystem::path program_;
  std::filesystem::path log_;
  pid_t pid_ = -1;
};

}  // namespace tachi::launcher
