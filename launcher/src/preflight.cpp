#include "preflight.hpp"

#include "tachi/common/process.hpp"
#include "tachi/launcher/supervision.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace tachi::launcher {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
// How long a node's flag check may take (run_flag_check: mostly the program's start).
constexpr std::chrono::seconds kFlagCheckDeadline{30};

// Measured on the bundled recordings (top_edge, grid 64, 5.6 s): cloth.obj ~172 B per particle, written
// twice (sim/ and --out); each journal ~95 B per hand sample; trace/ ~170 B per frame; an MPEG-4 frame of
// the 800 px viewer 0.8-3 KB, an MJPEG (.avi) one ~60 KB. Each figure below is that times 2-4, so a run
// that fits is never refused: the check is there to refuse a folder that obviously cannot hold the run.
constexpr double kObjBytesPerParticle = 400.0;
constexpr double kJournalBytesPerSample = 400.0;   // both journals together
constexpr double kTraceBytesPerFrame = 400.0;
constexpr double kMp4BytesPerPixelFrame = 0.02;    // 800 x 800: 12.8 KB a frame
constexpr double kAviBytesPerPixelFrame = 0.25;    // 800 x 800: 160 KB a frame
constexpr double kFixedBytes = 2.0e6;              // plots, final.png, summary, logs, config
constexpr double kLiveSecondsBudget = 60.0;        // a live run's length is unknown: room for a minute
constexpr double kSensorFps = 30.0;

// Seconds a recording plays (the last depth frame's timestamp minus the first's, fakenect's
// d-<seconds>-<ms>.pgm names) and its depth frames.
std::pair<double, std::size_t> recording_length(const fs::path& recording) {
  std::ifstream in(recording / "INDEX.txt");
  double first = 0.0, last = 0.0;
  std::size_t frames = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.starts_with("d-")) continue;
    const double t = std::strtod(line.c_str() + 2, nullptr);
    if (frames++ == 0) first = t;
    last = t;
  }
  return {std::max(0.0, last - first), frames};
}

double node_number(const RunConfig& config, const char* node, const char* flag, double fallback) {
  const auto options = config.node_options.value(node, nlohmann::json::object());
  const auto it = options.find(flag);
  if (it == options.end()) return fallback;
  if (it->is_number()) return it->get<double>();
  if (it->is_string()) {
    const double v = std::strtod(it->get<std::string>().c_str(), nullptr);
    return v > 0.0 ? v : fallback;
  }
  return fallback;
}

std::string human_bytes(std::uint64_t bytes) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed;
  if (bytes >= 1'000'000'000ULL) s << static_cast<double>(bytes) / 1e9 << " GB";
  else if (bytes >= 1'000'000ULL) s << static_cast<double>(bytes) / 1e6 << " MB";
  else s << static_cast<double>(bytes) / 1e3 << " KB";
  return s.str();
}

struct FlagCheck {
  int status = -1;     ///< waitpid status; -1: did not finish in time
  std::string output;  ///< what the node printed (its one line naming the flag)
};

// One node's command line with kCheckFlagsEnv set: it parses its flags and exits at once.
FlagCheck run_flag_check(const fs::path& program, const std::vector<std::string>& args) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error("cannot create a pipe to check the nodes' flags");
  // argv[0] is not the program's name, so that a look at the process table (ps, a test finding the
  // run's tachi-filter) never takes this short-lived check for the node itself.
  std::vector<std::string> argv_text{"flag-check-of-" + program.filename().string().substr(6)};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start " + program.string() + " to check its flags");
  if (pid == 0) {
    ::setenv(common::kCheckFlagsEnv, "1", 1);
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  FlagCheck result;
  // Parsing flags takes milliseconds, but starting the program does not: tachi-viewer loads 264 shared
  // libraries (OpenCV's video and image codecs, Qt), 0.45 s of CPU before main, and took 4-7 s of wall time
  // with 14 runnable tasks on two cores; a full ctest beside two builds ran past 10 s (2026-12-06). A node
  // still busy after this long ignored the check.
  const auto deadline = Clock::now() + kFlagCheckDeadline;
  char buffer[4096];
  while (Clock::now() < deadline) {
    pollfd p{pipe_fds[0], POLLIN, 0};
    if (::poll(&p, 1, 100) > 0) {
      const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
      if (n <= 0) break;  // closed: the node exited
      if (result.output.size() < 64 * 1024) result.output.append(buffer, static_cast<std::size_t>(n));
    }
  }
  ::close(pipe_fds[0]);
  int status = 0;
  if (::waitpid(pid, &status, WNOHANG) == 0) {
    const auto wait_until = Clock::now() + std::chrono::seconds(1);
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (Clock::now() > wait_until) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        return result;
      }
      ::usleep(10'000);
    }
  }
  result.status = status;
  return result;
}

// The user's setting that put `flag` on `node`'s command line: "--set sim.materal=denim" style for a
// pass-through option, the run flag for the ones the launcher derives.
std::string setting_of(const RunConfig& config, const std::string& node, const std::string& output) {
  const auto options = config.node_options.value(node, nlohmann::json::object());
  for (const auto& [flag, value] : options.items()) {
    // The node names the flag as given ("--materal"); match the whole flag, not a prefix of a longer one.
    const std::string dashed = "--" + flag;
    for (auto at = output.find(dashed); at != std::string::npos; at = output.find(dashed, at + 1)) {
      const auto end = at + dashed.size();
      if (end < output.size() && (std::isalnum(static_cast<unsigned char>(output[end])) || output[end] == '-' || output[end] == '_'))
        continue;
      const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
      return "--set " + node + "." + flag + "=" + text + " (or \"" + node + "\": {\"" + flag + "\": ...} in --config)";
    }
  }
  if (node == "sim" && output.find("--blade") != std::string::npos) return "--blade " + config.blade;
  return "the " + node + " node's options";
}

std::string first_line(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) return line;
  return text;
}

}  // namespace

std::uint64_t estimate_output_bytes(const RunConfig& config) {
  double seconds = kLiveSecondsBudget;
  double frames = kLiveSecondsBudget * kSensorFps;
  if (!config.recording.empty()) {
    const auto [length_s, depth_frames] = recording_length(config.recording);
    seconds = length_s + config.settle_s + 2.0;  // the cloth settles, the nodes stop
    frames = static_cast<double>(depth_frames);
  }
  const double particles = static_cast<double>(config.grid) * config.grid;
  double bytes = kFixedBytes + particles * kObjBytesPerParticle + frames * (kJournalBytesPerSample + kTraceBytesPerFrame);
  if (!config.video.empty() && config.has("viewer")) {
    const double fps = node_number(config, "viewer", "fps", 30.0);
    const double size = node_number(config, "viewer", "size", 800.0);
    const double per_pixel = config.video.ends_with(".avi") ? kAviBytesPerPixelFrame : kMp4BytesPerPixelFrame;
    bytes += seconds * fps * size * size * per_pixel;
  }
  return static_cast<std::uint64_t>(std::ceil(bytes));
}

std::optional<PreflightError> check_out_folder(const RunConfig& config, std::uint64_t needed_bytes) {
  const fs::path out(config.out);
  const auto fail = [&](const std::string& why) {
    return PreflightError{"--out " + config.out + ": " + why, kRunFailure};
  };
  // The nearest existing ancestor must be a folder: a file in the way is named.
  std::error_code ec;
  for (fs::path p = fs::absolute(out, ec); !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, ec)) {
      if (!fs::is_directory(p, ec))
        return fail(p == fs::absolute(out) ? "is a file, not a folder" : p.string() + " is a file, not a folder");
      break;
    }
    if (p == p.parent_path()) break;
  }
  fs::create_directories(out, ec);
  if (ec) return fail("cannot create the folder (" + ec.message() + ")");
  if (::access(out.c_str(), W_OK | X_OK) != 0) return fail("the folder is not writable (" + std::string(std::strerror(errno)) + ")");
  // access() answers for permissions only: a read-only mount says so when written.
  const fs::path probe = out / ".tachi-write-check";
  {
    std::ofstream f(probe);
    f << "x";
    f.flush();
    if (!f) {
      fs::remove(probe, ec);
      return fail("the folder is not writable (a test file could not be written)");
    }
  }
  fs::remove(probe, ec);
  const auto space = fs::space(out, ec);
  if (ec) return fail("cannot tell the free space (" + ec.message() + ")");
  // A previous run's outputs there are removed before this run writes: their room counts as free.
  std::uint64_t reclaimable = 0;
  for (const auto& entry : fs::recursive_directory_iterator(out, fs::directory_options::skip_permission_denied, ec))
    if (entry.is_regular_file(ec)) reclaimable += entry.file_size(ec);
  if (space.available + reclaimable < needed_bytes)
    return PreflightError{"--out " + config.out + ": " + human_bytes(space.available) + " free, but this run writes up to about " + human_bytes(needed_bytes) +
                " there (grid " + std::to_string(config.grid) + (config.video.empty() ? "" : ", " + config.video) +
                "); free some space or choose another --out",
                          kRunDiskFull};
  return std::nullopt;
}

std::optional<PreflightError> check_node_flags(const RunConfig& config, const fs::path& bin_dir) {
  // Each node's flags by its own executable (errors name the node's setting), then, in_process, the
  // composition's command line as tachi-pipeline reads it.
  auto specs = plan(config);
  if (config.in_process) specs.push_back(composed(specs));
  for (const auto& spec : specs) {
    const fs::path program = bin_dir / spec.program;
    if (::access(program.c_str(), X_OK) != 0)
      return PreflightError{spec.program + " not found next to tachi (" + program.string() + ")", kRunFailure};
    const FlagCheck check = run_flag_check(program, spec.args);
    if (check.status == -1)
      return PreflightError{spec.program + " did not answer the flag check within " +
                                std::to_string(kFlagCheckDeadline.count()) + " s",
                            kRunFailure};
    if (WIFEXITED(check.status) && WEXITSTATUS(check.status) == 0) continue;
    const std::string reason = first_line(check.output);
    if (WIFEXITED(check.status) && WEXITSTATUS(check.status) == kRunUsage)
      return PreflightError{setting_of(config, spec.node, check.output) + ": " + reason, kRunUsage};
    return PreflightError{spec.program + " refused its command line (" +
                              (WIFEXITED(check.status) ? "exit " + std::to_string(WEXITSTATUS(check.status))
                                                       : "signal " + std::to_string(WTERMSIG(check.status))) +
                              "): " + reason,
                          kRunFailure};
  }
  return std::nullopt;
}

}  // namespace tachi::launcher
