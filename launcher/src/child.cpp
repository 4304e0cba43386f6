#include "tachi/launcher/child.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace tachi::launcher {

Child::Child(ChildSpec spec, std::filesystem::path program, std::filesystem::path log)
    : spec_(std::move(spec)), program_(std::move(program)), log_(std::move(log)) {}

Child::~Child() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
}

std::string Child::command_line() const {
  std::string line = program_.string();
  for (const auto& a : spec_.args) {
    const bool plain = !a.empty() && a.find_first_of(" \t\"'$\\") == std::string::npos;
    line += " " + (plain ? a : "'" + a + "'");
  }
  return line;
}

void Child::start() {
  if (pid_ > 0) throw std::logic_error(spec_.program + " is already running");
  if (::access(program_.c_str(), X_OK) != 0) throw std::runtime_error("cannot run " + program_.string() + ": " + std::strerror(errno));
  const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write log " + log_.string() + ": " + std::strerror(errno));
  const std::string banner = "=== " + command_line() + "\n";
  if (::write(fd, banner.data(), banner.size()) < 0) { /* the log is best effort; the child still runs */ }

  std::vector<std::string> args{program_.string()};
  args.insert(args.end(), spec_.args.begin(), spec_.args.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();

  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    throw std::runtime_error("fork for " + spec_.program + ": " + std::strerror(errno));
  }
  if (pid == 0) {
    // Only async-signal-safe calls from here to exec.
    ::setpgid(0, 0);
    // The launcher's death ends the run (no one is left to supervise or write the summary): every
    // child goes at once. SIGKILL, not SIGTERM: each node's state is on disk as it goes (the journals,
    // the sensor's progress), and a graceful stop under load took 1.3-2.6 s (acks awaited from readers
    // dying at the same moment). The one loss is the viewer's video index, as when the viewer alone is
    // killed (docs/reliability.md). The launcher's own SIGINT/SIGTERM still stops the children gracefully.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the launcher died before prctl took effect
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, STDIN_FILENO);
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    ::sigaction(SIGINT, &dfl, nullptr);
    ::sigaction(SIGTERM, &dfl, nullptr);
    sigset_t go;
    ::sigemptyset(&go);
    ::sigaddset(&go, SIGUSR1);
    ::sigprocmask(spec_.waits_for_sigusr1 ? SIG_BLOCK : SIG_UNBLOCK, &go, nullptr);  // the mask survives exec
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(fd);
  pid_ = pid;
}

std::optional<int> Child::poll() {
  if (pid_ <= 0) return std::nullopt;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r != pid_) return std::nullopt;
  pid_ = -1;
  return status;
}

void Child::signal(int signo) const {
  if (pid_ > 0) ::kill(pid_, signo);
}

std::string Child::last_log_lines(int n) const {
  std::ifstream in(log_);
  std::deque<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string text;
  for (const auto& l : lines) text += "  | " + l + "\n";
  return text;
}

}  // namespace tachi::launcher
