// Child processes for multi-process tests: start a real executable, capture its stdout and
// stderr, wait with a deadline, and kill it if it overstays (a hung peer must fail the test,
// not hang ctest).
#pragma once

#include <sys/types.h>

#include <array>
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace tachi::test {

class ChildProcess {
 public:
  /// Starts `argv[0]` with the given arguments; `env` entries are added to the environment.
  explicit ChildProcess(std::vector<std::string> argv, const std::map<std::string, std::string>& env = {});
  ~ChildProcess();  // kills the child if still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// Waits for exit; returns the exit code, or -1 if it had to be killed at the deadline
  /// (or died by a signal).
  int wait(std::chrono::milliseconds timeout);
  /// Sends a signal (e.g. SIGINT to test a clean stop).
  void signal(int signo);
  /// Whether the child is still running; reads what it wrote meanwhile (out(), err()).
  bool running();
  pid_t pid() const { return pid_; }
  /// Reads the child's output until stdout contains `text` (true) or the timeout passes or the
  /// child exits without printing it (false).
  bool wait_for_output(const std::string& text, std::chrono::milliseconds timeout);

  /// Everything the child wrote so far (complete after wait()).
  const std::string& out() const { return out_; }
  const std::string& err() const { return err_; }

 private:
  void drain(int timeout_ms);
  pid_t pid_ = -1;
  int out_fd_ = -1;
  int err_fd_ = -1;
  int status_ = 0;
  bool exited_ = false;
  std::string out_;
  std::string err_;
};

/// Convenience: run to completion with a deadline.
struct RunResult {
  int exit_code;
  std::string out;
  std::string err;
};
RunResult run(std::vector<std::string> argv, std::chrono::milliseconds timeout,
              const std::map<std::string, std::string>& env = {});

/// A pipe whose buffer is full, as a reader that went away leaves it: {read end, write end}, the write end
/// blocking (as a process's stderr is), so the next write() to it would wait for a reader.
std::array<int, 2> full_pipe();

}  // namespace tachi::test
