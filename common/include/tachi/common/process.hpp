// The conventions every tachi process shares that need no flag parser: the bus flags' values, stopping on
// SIGINT/SIGTERM, the log level, the flags-only check. app.hpp adds the CLI11 side (it includes this header);
// a translation unit that parses no flags includes only this one, which keeps CLI11 out of it.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <string>

namespace tachi::common {

/// Flags every process that joins the DDS bus understands.
struct BusOptions {
  unsigned domain = 0;         ///< DDS domain id (0..232)
  std::string dds_config;      ///< Cyclone XML file; empty = the loopback config built in
  std::string secure_dir;      ///< DDS Security files (scripts/make_test_pki.sh); empty = no security
  std::string identity;        ///< whose certificate and grant to use; default: the program's name without "tachi-"
};

/// Set (to anything non-empty) when a process should check its flags and exit (see parse()).
inline constexpr const char* kCheckFlagsEnv = "TACHI_CHECK_FLAGS";

/// Sets spdlog's level from a name (trace, debug, info, warn, error, critical, off).
void set_log_level(const std::string& level);

/// Installs SIGINT/SIGTERM handlers that raise the stop flag instead of killing the process.
void install_stop_handlers();
/// True once SIGINT or SIGTERM has arrived (or request_stop was called).
bool stop_requested();
void request_stop();

/// Sleeps until `until` or a stop request, whichever comes first (it wakes every 10 ms to look), so
/// a long wait never outlasts SIGINT/SIGTERM by more than that. False when a stop ended it.
bool sleep_unless_stopped(std::chrono::steady_clock::time_point until);

/// Calls `tick` until it returns false or a stop is requested, and every 10 s gives the allocator's free
/// pages back to the system (malloc_trim). `tick` is expected to block briefly (e.g. on a DDS waitset) so
/// this does not spin. Sets the allocator up for a long run first (keep_large_blocks_mapped).
void run_until_stopped(const std::function<bool()>& tick);

/// For the rest of the process, a block of 128 KiB or more that the heap has no fitting free chunk for
/// gets its own mapping, given back to the system when it is freed (a free chunk that fits is still used
/// first: the threshold applies only when there is none). Without this, glibc's threshold rises to the size
/// of each mapped block freed, so after the first of Cyclone's receive buffers was freed the later ones
/// came from a thread's heap, whose freed pages stay resident until a trim (docs/benchmarks.md, "Soak").
/// Called by the long-running loops.
void keep_large_blocks_mapped();

}  // namespace tachi::common
