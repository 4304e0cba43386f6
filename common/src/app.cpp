#include "tachi/common/app.hpp"

#include "tachi/common/log_sink.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>  // declares stderr_color_mt too
#include <spdlog/spdlog.h>

#include <malloc.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <optional>
#include <thread>
#include <iostream>

namespace tachi::common {
namespace {
std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag is written from a signal handler");

extern "C" void on_stop_signal(int /*signal*/) { g_stop.store(true); }

const std::map<std::string, spdlog::level::level_enum> kLevels{
    {"trace", spdlog::level::trace}, {"debug", spdlog::level::debug}, {"info", spdlog::level::info},
    {"warn", spdlog::level::warn},   {"error", spdlog::level::err},   {"critical", spdlog::level::critical},
    {"off", spdlog::level::off}};
// CLI11's Range and NonNegativeNumber compare with < and >, which NaN passes, and a number too
// large for a double reads as inf: so every value given to any flag that reads as a number must be
// finite. One check here covers every flag of every executable, present and future.
std::optional<std::string> first_non_finite_value(const CLI::App& app) {
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& value : option->results()) {
      const char* begin = value.c_str();
      char* end = nullptr;
      const double number = std::strtod(begin, &end);
      if (end != begin && *end == '\0' && !std::isfinite(number))
        return option->get_name() + ": " + value + " is not a finite number";
    }
  }
  for (const CLI::App* sub : app.get_subcommands())
    if (auto bad = first_non_finite_value(*sub)) return bad;
  return std::nullopt;
}
}  // namespace

void add_log_level_flag(CLI::App& app, std::string& level) {
  if (level.empty()) level = "info";
  app.add_option("--log-level", level, "Log verbosity")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
}

void add_bus_flags(CLI::App& app, BusOptions& options) {
  app.add_option("--domain", options.domain, "DDS domain id; processes of one pipeline share it")
      ->check(CLI::Range(0u, 232u))
      ->capture_default_str();
  app.add_option("--dds-config", options.dds_config,
                 "Cyclone DDS XML config; default: the built-in loopback-only config (config/cyclonedds-loopback.xml)")
      ->check(CLI::ExistingFile);
  app.add_option("--secure", options.secure_dir,
                 "DDS Security: authenticate, access-control and encrypt with the certificates and grants in DIR "
                 "(made by scripts/make_test_pki.sh; docs/reliability.md)")
      ->check(CLI::ExistingDirectory);
  // tachi-filter is "filter": each node's grant names only its own topics.
  std::string name = app.get_name();
  if (name.starts_with("tachi-")) name.erase(0, 6);
  if (options.identity.empty()) options.identity = name;
  app.add_option("--identity", options.identity, "With --secure: the identity (DIR/NAME.cert.pem and its grant) to use")
      ->capture_default_str();
}

int parse(CLI::App& app, int argc, char** argv) {
  // Logs go to stderr, named after the program: stdout carries CSV/JSON output. Never blocking on it
  // (log_sink.hpp): a process must not stop because nobody reads its log.
  if (spdlog::get(app.get_name()) == nullptr) spdlog::set_default_logger(stderr_logger(app.get_name()));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return kExitOk;
  } catch (const CLI::CallForVersion& v) {
    std::cout << v.what() << '\n';
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    std::cerr << app.get_name() << ": " << e.what() << '\n';
    return kExitUsage;
  }
  if (const auto bad = first_non_finite_value(app)) {
    std::cerr << app.get_name() << ": " << *bad << '\n';
    return kExitUsage;
  }
  // `tachi run` checks every node's command line before it starts any node: the flags parse (exit 0)
  // or the one line naming the bad flag comes now (exit 2), not seconds into a run.
  if (const char* check = std::getenv(kCheckFlagsEnv); check != nullptr && *check != '\0') return kExitOk;
  return -1;
}

void set_log_level(const std::string& level) {
  const auto it = kLevels.find(level);
  spdlog::set_level(it == kLevels.end() ? spdlog::level::info : it->second);
}

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() { return g_stop.load(); }
void request_stop() { g_stop.store(true); }

bool sleep_unless_stopped(std::chrono::steady_clock::time_point until) {
  constexpr auto kSlice = std::chrono::milliseconds(10);
  while (!stop_requested()) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= until) return true;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(until - now, kSlice));
  }
  return false;
}

void run_until_stopped(const std::function<bool()>& tick) {
  // A long run gives freed memory back: glibc keeps it in its arenas (one per thread that allocates, and
  // Cyclone's receive threads allocate the samples the node's thread frees), so in the one-hour soak a node
  // whose heap was flat saw its resident memory wander by up to 15 % (docs/benchmarks.md, "Soak").
  // malloc_trim(0) returns every arena's free pages, not only the heap's top; every 10 s it costs nothing
  // a frame would notice.
  keep_large_blocks_mapped();
  constexpr auto kTrimPeriod = std::chrono::seconds(10);
  auto next_trim = std::chrono::steady_clock::now() + kTrimPeriod;
  while (!stop_requested()) {
    if (!tick()) break;
    if (const auto now = std::chrono::steady_clock::now(); now >= next_trim) {
      ::malloc_trim(0);
      next_trim = now + kTrimPeriod;
    }
  }
}

void keep_large_blocks_mapped() {
  // 128 KiB is glibc's starting threshold; setting it also turns the rise off. The threshold applies to a
  // block the heap has no free room for (a free chunk that fits is used first); with the rise off the
  // heap's free top is trimmed at 128 KiB too, so in a node the large blocks are mapped (malloc_info in a
  // looped filter: both receive buffers mapped). What it costs: an mmap and munmap per large block (the
  // receive buffers, a 128 x 128 cloth state), whose page faults a fresh heap block would pay too;
  // tachi-sensor's time per frame did not move (0.71-0.74 ms against 0.70-0.83 ms,
  // tachi-sensor-process-bench, the same period).
  constexpr int kLargeBlock = 128 * 1024;
  ::mallopt(M_MMAP_THRESHOLD, kLargeBlock);
}

}  // namespace tachi::common
