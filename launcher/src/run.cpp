#include "run.hpp"

#include "bus_adapter.hpp"
#include "tachi/common/process.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/launcher/child.hpp"
#include "tachi/launcher/status.hpp"
#include "tachi/launcher/supervision.hpp"

#include <spdlog/spdlog.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <csignal>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>

namespace tachi::launcher {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

struct Supervised {
  std::unique_ptr<Child> child;
  RestartPolicy policy;
  std::optional<Clock::time_point> restart_at;
  bool done = false;
  int restarts = 0;
  std::optional<Clock::time_point> died_at;  ///< until its restarted process reports for the first time
};

// A killed viewer's unfinished video (it plays up to its last fragment) is kept aside, not overwritten by the
// restarted viewer's, which starts where the run is now.
void keep_aside_partial_video(const RunConfig& config, int restart) {
  if (config.video.empty()) return;
  const fs::path video = fs::path(config.out) / config.video;
  if (!fs::exists(video)) return;
  const fs::path aside =
      video.parent_path() / (video.stem().string() + ".before-restart-" + std::to_string(restart) + video.extension().string());
  std::error_code ec;
  fs::rename(video, aside, ec);
  if (ec) spdlog::warn("cannot move {} aside: {}", video.string(), ec.message());
  else spdlog::warn("the killed viewer's unfinished video is {}", aside.string());
}

constexpr const char* kLossyConfigFile = "cyclonedds-lossy.xml";
static_assert(kMaxLossyPermille == bus::kMaxTransmitLossPermille, "tachi run's --lossy bound is the bus's");

// `tachi run --lossy`: every participant of the run (the nodes, restarted ones too, and the
// launcher's monitor) reads one lossy config, written into the run's folder, where a user also finds
// what the run used.
RunConfig with_lossy_link(const RunConfig& requested, const fs::path& out) {
  if (requested.lossy_permille == 0) return requested;
  RunConfig config = requested;
  config.dds_config = (fs::absolute(out) / kLossyConfigFile).string();
  std::ofstream file(config.dds_config);
  file << bus::lossy_config_xml(bus::dds_config_xml(requested.dds_config), requested.lossy_permille);
  if (!file.flush()) throw std::runtime_error("--lossy: cannot write " + config.dds_config);
  spdlog::info("lossy link: every node drops {} of 1000 packets it sends ({})", requested.lossy_permille, config.dds_config);
  if (requested.in_process)
    spdlog::warn("--lossy with --in-process: the nodes share one process, where samples never cross the network; "
                 "only the launcher's monitor (and other hosts) see the loss");
  return config;
}

// A previous run's results in the same folder must not pass for this run's.
void clear_outputs(const fs::path& out) {
  fs::create_directories(out);
  for (const auto* name : {"summary.json", "cloth.obj", "pattern.svg", "final.png", "video.mp4", "video.avi",
                           "latency.png", "trajectory.png", "config.json", "sim.journal", "filter.journal",
                           "sensor.progress", kLossyConfigFile})
    fs::remove(out / name);
  fs::remove_all(out / kSimExportDir);
  fs::remove_all(out / "trace");
  for (const auto& entry : fs::directory_iterator(out))
    if (entry.path().extension() == ".log" || entry.path().stem().string().find(".before-restart-") != std::string::npos)
      fs::remove(entry.path());
}

// Room for summary.json is taken when the run starts, so that a disk filling up during the run still
// leaves the summary: it is written over the reserved blocks at the end, then cut to its length.
class ReservedFile {
 public:
  static constexpr off_t kReserve = 256 * 1024;  // a summary is a few KB; its per-node figures grow with nodes, not time
  explicit ReservedFile(fs::path file) : file_(std::move(file)) {
    fd_ = ::open(file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ >= 0 && ::posix_fallocate(fd_, 0, kReserve) != 0) spdlog::warn("{}: cannot reserve room for it", file_.string());
  }
  ReservedFile(const ReservedFile&) = delete;
  ReservedFile& operator=(const ReservedFile&) = delete;
  ~ReservedFile() {
    if (fd_ >= 0) ::close(fd_);
    std::error_code ec;
    if (!written_) fs::remove(file_, ec);  // a run that threw leaves no zero-filled summary behind
  }
  /// Writes `text` as the whole file; throws DiskFull or std::runtime_error naming it.
  void write(const std::string& text) {
    if (fd_ < 0) fd_ = ::open(file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    bool ok = fd_ >= 0;
    for (std::size_t done = 0; ok && done < text.size();) {
      const ssize_t n = ::pwrite(fd_, text.data() + done, text.size() - done, static_cast<off_t>(done));
      ok = n > 0;
      if (ok) done += static_cast<std::size_t>(n);
    }
    ok = ok && ::ftruncate(fd_, static_cast<off_t>(text.size())) == 0;
    if (!ok) common::throw_write_error(file_, "cannot write " + file_.string() + ": " + std::strerror(errno));
    written_ = true;
  }

 private:
  fs::path file_;
  int fd_ = -1;
  bool written_ = false;
};

// The simulator's summary.json, merged into the run's.
nlohmann::json read_sim_summary(const fs::path& out) {
  const fs::path file = out / kSimExportDir / "summary.json";
  if (!fs::is_regular_file(file)) return nlohmann::json::object();
  std::ifstream in(file);
  nlohmann::json sim = nlohmann::json::parse(in, nullptr, false);
  if (!sim.is_object()) {
    spdlog::warn("{}: not a JSON object; the simulator's figures are missing from summary.json", file.string());
    return nlohmann::json::object();
  }
  return sim;
}

// Every other file the simulator exported (cloth.obj, pattern.svg, ...) next to the run's summary.
void copy_sim_export(const fs::path& out) {
  const fs::path dir = out / kSimExportDir;
  if (!fs::is_directory(dir)) return;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename() != "summary.json" && entry.is_regular_file())
      fs::copy_file(entry.path(), out / entry.path().filename(), fs::copy_options::overwrite_existing);
}

nlohmann::json make_summary(const RunConfig& config, const StatusBoard& board, const nlohmann::json& sim,
                            std::uint64_t cut_events, int restarts, const nlohmann::json& recoveries,
                            const std::string& ended) {
  nlohmann::json s = sim;  // the simulator's own figures (pieces, cut line, ...) are authoritative
  const nlohmann::json beats = board.summary();
  for (const auto& [key, value] : beats.items())
    if (!s.contains(key) || key.find("_p50_ms") != std::string::npos || key.find("_p99_ms") != std::string::npos)
      s[key] = value;
  if (!s.contains("e2e_p50_ms") && sim.contains("latency_p50_ms")) {
    s["e2e_p50_ms"] = sim["latency_p50_ms"];
    s["e2e_p99_ms"] = sim["latency_p99_ms"];
  }
  if (!s.contains("cuts")) s["cuts"] = cut_events;
  // The fields are always there: counts default to 0, figures nobody measured to null.
  for (const char* key : {"frames", "tracked_frames", "strokes", "cuts", "pieces", "fallen_pieces", "cut_length_m"})
    if (!s.contains(key)) s[key] = 0;
  for (const char* stage : {"e2e", "sensor", "filter", "sim", "viewer"})
    for (const char* p : {"_p50_ms", "_p99_ms"})
      if (!s.contains(std::string(stage) + p)) s[std::string(stage) + p] = nullptr;
  s["restarts"] = restarts;
  s["recoveries"] = recoveries;
  s["nodes"] = to_json(config)["nodes"];
  s["domain"] = config.domain;
  s["source"] = config.recording.empty() ? "live" : config.recording;
  s["ended"] = ended;
  return s;
}

// The plotter starts with the run and imports matplotlib meanwhile (~1 s a run would otherwise end
// later); it draws once sent SIGUSR1, after the summary is written (scripts/plot_run.py --after-sigusr1).
std::unique_ptr<Child> start_plotter(const RunPaths& paths, const fs::path& out) {
  if (!fs::exists(paths.plot_script)) {
    spdlog::warn("no plots: {} not found", paths.plot_script.string());
    return nullptr;
  }
  ChildSpec spec{"plot", "python3", {paths.plot_script.string(), "--after-sigusr1", out.string()}, true};
  spec.waits_for_sigusr1 = true;
  auto plotter = std::make_unique<Child>(std::move(spec), "/usr/bin/python3", out / "plot.log");
  plotter->start();
  return plotter;
}

void draw_plots(Child* plotter) {
  if (!plotter) return;
  plotter->signal(SIGUSR1);
  const auto deadline = Clock::now() + 60s;
  while (Clock::now() < deadline) {
    if (const auto status = plotter->poll()) {
      if (classify_exit(*status, true) != ExitMeaning::Done)
        spdlog::warn("plots failed ({}):\n{}", describe_exit(*status), plotter->last_log_lines(5));
      return;
    }
    std::this_thread::sleep_for(20ms);
  }
  spdlog::warn("plots took over 60 s; given up");
}

}  // namespace

fs::path plot_script(const fs::path& bin_dir) { return bin_dir.parent_path() / "share" / "tachi" / "plot_run.py"; }

int run(const RunConfig& requested, const RunPaths& paths) {
  // The nodes share the machine: a simulator on two threads waits for its other thread passively instead
  // of spinning a core the other nodes need (libgomp reads this at start; a value the user set wins). On
  // the loaded 2-core machine spinning made two threads 0.06x as fast as one, passive 0.70x
  // (docs/benchmarks.md, "Threads").
  ::setenv("OMP_WAIT_POLICY", "passive", 0);
  const fs::path out(requested.out);
  clear_outputs(out);
  ReservedFile summary_file(out / "summary.json");
  {
    std::ofstream cfg(out / "config.json");
    cfg << to_json(requested).dump(2) << '\n';
  }
  const RunConfig config = with_lossy_link(requested, out);
  // With DDS Security the launcher reads as "monitor", the identity that may read every topic.
  bus::Participant dds{config.domain, config.dds_config, {config.secure, "monitor"}};
  RunMonitor monitor{dds, out / "trace"};
  StatusBoard board;

  std::vector<Supervised> children;
  for (auto& spec : children_of(config)) {
    const fs::path program = paths.bin_dir / spec.program;
    const fs::path log = out / (spec.node + ".log");
    children.push_back({std::make_unique<Child>(std::move(spec), program, log), RestartPolicy{}, {}, false, 0, {}});
  }
  const auto plotter = start_plotter(paths, out);
  const bool recording = !config.recording.empty();
  spdlog::info("run on DDS domain {}: {} ({}); outputs in {}", config.domain, to_json(config)["nodes"].get<std::string>(),
               recording ? "recording " + config.recording : "live", out.string());
  std::vector<std::string> started;
  for (auto& c : children) {
    // Consumers first. The sensor starts once the others said they are up (their first heartbeat:
    // their readers and writers exist and are being discovered), so a recording's first frames are not lost.
    if (c.child->spec().node == "sensor") {
      const auto deadline = Clock::now() + 5s;
      const auto all_up = [&] {
        for (const auto& program : started)
          if (!board.nodes().contains(program)) return false;
        return true;
      };
      while (!all_up() && Clock::now() < deadline && !common::stop_requested()) monitor.poll(board, 50ms);
      monitor.poll(board, 200ms);
    }
    c.child->start();
    started.push_back(c.child->spec().program);
    spdlog::info("started {} (pid {})", c.child->spec().program, c.child->pid());
  }

  const bool tty = ::isatty(STDERR_FILENO) == 1;
  auto last_status = Clock::now();
  int restarts = 0;
  nlohmann::json recoveries = nlohmann::json::array();
  int exit_code = kRunOk;
  std::string ended = "stopped";
  std::optional<Clock::time_point> finite_done_at, upstream_done_at;
  // The run's most upstream producer: the sensor, or on a host without one (--nodes sim,viewer) the
  // simulator. Once it finished, nothing more will come to the nodes after it.
  const std::string upstream = config.has("sensor") ? "sensor" : config.has("sim") ? "sim" : "";
  bool viewer_closed = false;
  while (true) {
    monitor.poll(board, 100ms);
    if (common::stop_requested()) {
      ended = "stopped by signal";
      break;
    }
    const auto now = Clock::now();
    bool failed = false;
    for (auto& c : children) {
      const auto& spec = c.child->spec();
      if (c.restart_at && now >= *c.restart_at) {
        c.restart_at.reset();
        if (spec.node == "viewer") keep_aside_partial_video(config, c.restarts);
        c.child->start();
        spdlog::info("restarted {} (pid {})", spec.program, c.child->pid());
      }
      const auto status = c.child->poll();
      if (!status) continue;
      const ExitMeaning meaning = classify_exit(*status, spec.finite);
      switch (meaning) {
        case ExitMeaning::Done:
          c.done = true;
          spdlog::info("{} finished", spec.program);
          if (spec.node == upstream) upstream_done_at = now;
          // Live, a composed pipeline ends by itself only when its viewer's window closed.
          if ((spec.node == "viewer" || spec.node == "pipeline") && !recording) viewer_closed = true;
          break;
        case ExitMeaning::DiskFull:
          // The node logged "<file>: no space left on device" itself: that line once for the run (nodes writing
          // to one full disk often stop in the same moment; the first names it), no restart.
          if (exit_code != kRunDiskFull) {
            spdlog::error("{} stopped the run: {}", spec.program, c.child->last_log_lines(1));
            ended = "disk full (" + spec.program + ")";
          }
          exit_code = kRunDiskFull;
          failed = true;
          break;
        case ExitMeaning::Usage:
        case ExitMeaning::NoDevice: {
          spdlog::error("{} cannot run ({}); its log {} ends:\n{}", spec.program, describe_exit(*status), c.child->log().string(),
                        c.child->last_log_lines(10));
          exit_code = meaning == ExitMeaning::Usage ? kRunUsage : kRunNoDevice;
          ended = spec.program + " " + describe_exit(*status);
          failed = true;
          break;
        }
        case ExitMeaning::Died: {
          const auto decision = c.policy.on_death(now);
          if (decision.give_up) {
            spdlog::error("{} died {} times within 30 s (last: {}); stopping the run. Its log {} ends:\n{}", spec.program,
                          c.policy.deaths_in_window(), describe_exit(*status), c.child->log().string(),
                          c.child->last_log_lines(10));
            exit_code = kRunChildGaveUp;
            ended = spec.program + " kept dying";
            failed = true;
            break;
          }
          ++restarts;
          ++c.restarts;
          c.restart_at = now + decision.delay;
          c.died_at = now;
          spdlog::warn("{} died ({}); restart {} in {} ms", spec.program, describe_exit(*status), c.restarts,
                       decision.delay.count());
          break;
        }
      }
    }
    if (failed) break;
    if (const auto& file = monitor.disk_full()) {
      spdlog::error("{}: no space left on device", file->string());
      exit_code = kRunDiskFull;
      ended = "disk full (" + file->filename().string() + ")";
      break;
    }
    // Recovered: the restarted process reported (its first heartbeat: it is up and, for the simulator,
    // has replayed its journal). From the death to that report, backoff included.
    for (auto& c : children) {
      if (!c.died_at || c.restart_at || !c.child->running()) continue;
      // Its heartbeat (any node's, for tachi-pipeline's composed nodes) comes from the new process.
      const auto pid = static_cast<std::uint32_t>(c.child->pid());
      if (std::none_of(board.nodes().begin(), board.nodes().end(), [&](const auto& n) { return n.second.pid == pid; })) continue;
      const double ms = std::chrono::duration<double, std::milli>(now - *c.died_at).count();
      recoveries.push_back({{"node", c.child->spec().node}, {"restart", c.restarts}, {"recovery_ms", std::round(ms)}});
      spdlog::info("{} recovered {:.0f} ms after it died", c.child->spec().program, ms);
      c.died_at.reset();
    }
    if (viewer_closed) {
      ended = "viewer window closed";
      break;
    }

    if (recording) {
      bool all_finite_done = true, any_finite = false;
      for (const auto& c : children) {
        if (!c.child->spec().finite) continue;
        any_finite = true;
        all_finite_done = all_finite_done && c.done;
      }
      if (any_finite && all_finite_done) {
        // Non-finite nodes (the filter) get a moment to pass the last samples on before they stop,
        // unless this run's simulator, their reader, has finished: it stops only once idle.
        if (!finite_done_at) finite_done_at = now;
        if (now - *finite_done_at >= (config.has("sim") ? 0ms : 500ms)) {
          ended = "recording played, cloth settled";
          break;
        }
      }
      // A node that never saw the recording's samples (restarted after the sensor finished; on a host
      // without the sensor, a viewer that never got the cloth) would wait forever: the run ends.
      if (upstream_done_at && now - *upstream_done_at > std::chrono::duration<double>(config.settle_s + 20.0)) {
        std::string waiting;
        for (const auto& c : children)
          if (!c.done) waiting += (waiting.empty() ? "" : ", ") + c.child->spec().program;
        spdlog::warn("tachi-{} finished {:.0f} s ago and {} still waiting; stopping them", upstream, config.settle_s + 20.0,
                     waiting);
        ended = "recording played; nodes stopped after a timeout";
        break;
      }
    }

    if (tty && now - last_status >= 500ms) {
      std::cerr << "\r\033[K" << board.line(restarts) << std::flush;
      last_status = now;
    } else if (!tty && now - last_status >= 5s) {
      spdlog::info("status: {}", board.line(restarts));
      last_status = now;
    }
  }
  if (tty) std::cerr << '\n';

  // Children first: SIGINT lets each finish its frame and write its outputs (the simulator exports).
  for (auto& c : children) {
    c.restart_at.reset();
    c.child->signal(SIGINT);
  }
  const auto deadline = Clock::now() + 3s;
  for (auto& c : children) {
    while (c.child->running() && Clock::now() < deadline) {
      if (c.child->poll()) break;
      monitor.poll(board, 20ms);
    }
    if (c.child->running()) {
      spdlog::warn("{} did not stop within 3 s of SIGINT; killed", c.child->spec().program);
      c.child->signal(SIGKILL);
      while (!c.child->poll()) std::this_thread::sleep_for(10ms);
    }
  }
  monitor.poll(board, 200ms);  // the nodes' last heartbeats (NODE_STOPPING, final figures)

  // summary.json first: on a full disk it is what the run must leave; the copies and plots come after.
  const nlohmann::json sim = read_sim_summary(out);
  const nlohmann::json summary = make_summary(config, board, sim, monitor.cut_events(), restarts, recoveries, ended);
  try {
    summary_file.write(summary.dump(2) + '\n');
    copy_sim_export(out);
    draw_plots(plotter.get());
  } catch (const common::DiskFull& e) {
    if (exit_code != kRunDiskFull) spdlog::error("{}", e.what());  // a node already said the disk is full
    exit_code = kRunDiskFull;
  } catch (const fs::filesystem_error& e) {
    if (e.code() != std::errc::no_space_on_device) throw;
    if (exit_code != kRunDiskFull) spdlog::error("{}: no space left on device", e.path2().string());
    exit_code = kRunDiskFull;
  }
  // stdout: the headline figures (summary.json has them all), then where the outputs are.
  nlohmann::json headline = nlohmann::json::object();
  for (const char* key : {"frames", "tracked_frames", "strokes", "cuts", "pieces", "fallen_pieces", "cut_length_m",
                          "restarts", "e2e_p50_ms", "e2e_p99_ms"})
    headline[key] = summary[key];
  std::cout << headline.dump() << '\n' << "outputs in " << fs::absolute(out).string() << '\n';
  spdlog::info("run ended: {} ({} restarts)", ended, restarts);
  return exit_code;
}

}  // namespace tachi::launcher
