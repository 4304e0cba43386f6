// tachi-sim: the cloth simulator process. --offline runs the library's offline driver (no DDS); the
// live mode (publish topology/state, subscribe strokes) joins the DDS pipeline.
#include "tachi/common/app.hpp"
#include "tachi/sim/offline.hpp"

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  CLI::App app{"tachi-sim: mass-spring cloth simulator (Provot), collisions, grabbing, cutting"};
  app.name("tachi-sim");
  bool offline = false;
  std::string log_level = "info";
  tachi::sim::OfflineOptions options;
  app.add_flag("--offline", offline, "Run without DDS: simulate, then export the mesh and a summary");
  tachi::sim::add_offline_flags(app, options);
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;

  if (!offline) {
    std::cerr << "tachi-sim: live mode needs the DDS pipeline: not built yet; use --offline\n";
    return tachi::common::kExitUsage;
  }
  const tachi::sim::Summary summary = tachi::sim::run_offline(options);
  spdlog::info("{} steps of a {}x{} cloth: max strain {:.4f}, median step {:.3f} ms", summary.steps, summary.columns,
               summary.rows, summary.max_strain, summary.step_ms_median);
  if (options.export_dir.empty()) std::cout << tachi::sim::to_json(summary).dump(2) << '\n';
  return tachi::common::kExitOk;
} catch (const std::exception& e) {
  std::cerr << "tachi-sim: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
