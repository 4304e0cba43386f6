// Conventions every tachi executable shares, so that `main` stays a dozen lines:
// one way to parse flags (CLI11), one way to log (spdlog), one way to stop (SIGINT/SIGTERM),
// and one table of exit codes (exit_codes.hpp, documented in docs/cli.md). What needs no CLI11 (the bus
// flags' values, stopping, the log level) is in process.hpp: include that where no flags are parsed, as
// CLI/CLI.hpp costs every translation unit that includes it ~5 s of a cold build.
#pragma once

#include "tachi/common/exit_codes.hpp"
#include "tachi/common/process.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace tachi::common {

/// Adds `--log-level` to an app; the chosen level is applied by parse().
void add_log_level_flag(CLI::App& app, std::string& level);
/// Adds `--domain`, `--dds-config`, `--secure` and `--identity`.
void add_bus_flags(CLI::App& app, BusOptions& options);

/// Routes spdlog's default logger to stderr under the program's name, then parses argv. Returns an exit code when the process should stop now (help printed: 0;
/// bad flag: one line "<program>: <flag>: <reason>" on stderr, kExitUsage), else -1.
/// With the environment variable kCheckFlagsEnv set, a command line that parses returns kExitOk
/// at once: the process only checks its flags (tachi run's preflight).
int parse(CLI::App& app, int argc, char** argv);

}  // namespace tachi::common
