// `tachi run`: starts the pipeline's nodes as supervised children, shows the run's status from the
// heartbeats, stops everything cleanly, and leaves the outputs in --out (docs/cli.md "tachi run").
#pragma once

#include "tachi/launcher/config.hpp"

#include <filesystem>

namespace tachi::launcher {

struct RunPaths {
  std::filesystem::path bin_dir;      ///< where tachi-sensor, tachi-filter, ... are (next to tachi)
  std::filesystem::path plot_script;  ///< scripts/plot_run.py
};

/// The plotter beside `tachi`: <bin>/../share/tachi/plot_run.py (the build copies scripts/plot_run.py
/// there; found from the executable, not compiled in, so the build is the same in every checkout).
[[nodiscard]] std::filesystem::path plot_script(const std::filesystem::path& bin_dir);

/// Runs until the recording is played and the cloth settled, SIGINT/SIGTERM, or a child gives up.
/// Returns a RunExit code.
int run(const RunConfig& config, const RunPaths& paths);

}  // namespace tachi::launcher
