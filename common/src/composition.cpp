#include "tachi/common/composition.hpp"

#include "tachi/common/disk_full.hpp"
#include "tachi/common/exit_codes.hpp"
#include "tachi/common/log_sink.hpp"
#include "tachi/common/process.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace tachi::common {
namespace {

thread_local std::string t_node_name;  // the node whose thread this is ("" outside run_composed)

// spdlog pattern flag %*: ":<node>" on a node's thread, nothing elsewhere.
class NodeNameFlag final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg&, const std::tm&, spdlog::memory_buf_t& dest) override {
    if (t_node_name.empty()) return;
    dest.push_back(':');
    dest.append(t_node_name.data(), t_node_name.data() + t_node_name.size());
  }
  [[nodiscard]] std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<NodeNameFlag>(); }
};

// What the threads tell the composing thread.
struct Board {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<bool> finished;
  int failure_code = 0;  ///< a node that threw: its process-like exit code (guarded by mutex)
};

}  // namespace

void log_node_names(const std::string& logger_name) {
  // Each stage's flag parsing made its own logger the default (spdlog drops the one it replaces).
  auto logger = spdlog::get(logger_name);
  if (!logger) logger = stderr_logger(logger_name);  // never blocking on an unread stderr (log_sink.hpp)
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<NodeNameFlag>('*').set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%n%*] [%^%l%$] %v");
  logger->set_formatter(std::move(formatter));
  spdlog::set_default_logger(logger);
}

int run_composed(std::vector<ComposedNode> nodes, std::chrono::milliseconds grace) {
  install_stop_handlers();
  keep_large_blocks_mapped();  // a long run, as run_until_stopped's
  Board board;
  board.finished.assign(nodes.size(), false);
  // Each node's own stop, raised for all when the composition ends (the finite nodes done and the grace
  // over, or a node failed); SIGINT/SIGTERM raise the process-wide flag, which every node sees as well.
  std::vector<std::unique_ptr<std::atomic<bool>>> stop;
  std::vector<int> codes(nodes.size(), kExitOk);
  for (std::size_t i = 0; i < nodes.size(); ++i) stop.push_back(std::make_unique<std::atomic<bool>>(false));

  // One spin of node i, or its end: false once it has finished (its code and any failure on the board).
  const auto step = [&](std::size_t i) {
    ComposedNode& node = nodes[i];
    int code = kExitOk;
    bool threw = true;
    try {
      if (!stop_requested() && !stop[i]->load() && node.spin_once()) return true;
      code = node.finish();
      threw = false;
    } catch (const DiskFull& e) {
      spdlog::error("{}", e.what());  // the one line a full disk gets
      code = kExitDiskFull;
    } catch (const std::exception& e) {
      spdlog::error("{} failed: {}", node.name, e.what());
      code = kExitFailure;
    }
    {
      std::lock_guard lock(board.mutex);
      codes[i] = code;
      board.finished[i] = true;
      if (threw && board.failure_code == 0) board.failure_code = code;
    }
    board.changed.notify_all();
    return false;
  };

  // A window's node spins on this thread, the one that opened the window: GUI toolkits (OpenCV's Qt
  // highgui) refuse to be driven from another. The others get a thread each.
  std::optional<std::size_t> on_this_thread;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (nodes[i].needs_calling_thread && !on_this_thread) on_this_thread = i;
  std::vector<std::thread> threads;
  threads.reserve(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (on_this_thread == i) continue;
    threads.emplace_back([&, i] {
      t_node_name = nodes[i].name;
      while (step(i)) {
      }
    });
  }

  bool any_finite = false;
  for (const auto& n : nodes) any_finite = any_finite || n.finite;
  const auto finite_done = [&] {
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (nodes[i].finite && !board.finished[i]) return false;
    return true;
  };
  // Until a signal, a failed node (which ends the composition at once, as a dying process ends its run),
  // or the finite nodes done and the others' grace over. Between the window's spins, or woken by a node
  // that finished, or every 10 ms to see a signal (the stop flag is set in a handler).
  if (on_this_thread) t_node_name = nodes[*on_this_thread].name;
  std::optional<std::chrono::steady_clock::time_point> grace_ends;
  bool on_this_thread_runs = on_this_thread.has_value();
  while (!stop_requested()) {
    {
      std::unique_lock lock(board.mutex);
      if (board.failure_code != 0) break;
      if (any_finite && finite_done()) {
        if (!grace_ends) grace_ends = std::chrono::steady_clock::now() + grace;
        if (std::chrono::steady_clock::now() >= *grace_ends) break;
      }
      if (!on_this_thread_runs) {
        board.changed.wait_for(lock, std::chrono::milliseconds(10));
        continue;
      }
    }
    on_this_thread_runs = step(*on_this_thread);
  }
  for (auto& s : stop) s->store(true);
  if (on_this_thread_runs) step(*on_this_thread);  // stopped: it finishes, on its own thread
  t_node_name.clear();
  for (auto& t : threads) t.join();
  if (board.failure_code != 0) return board.failure_code;
  for (const int code : codes)
    if (code != kExitOk) return code;
  return kExitOk;
}

}  // namespace tachi::common
