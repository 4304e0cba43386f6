// `tachi`'s subcommands, each run from its parsed command line (cli.hpp): `run` prepares the run (config,
// checks, partition, a live pipeline on the domain) and hands it to launcher::run; the bus tools join the
// domain and print what they see.
#pragma once

#include "cli.hpp"

#include <filesystem>

namespace tachi::launcher {

/// Runs the command's subcommand; `bin_dir` holds the nodes' executables. The exit code.
int dispatch(const Command& command, const std::filesystem::path& bin_dir);

/// The folder of the running executable (the nodes are next to it).
std::filesystem::path self_dir(const char* argv0);

}  // namespace tachi::launcher
