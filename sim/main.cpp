// tachi-sim: the cloth simulator process. --offline runs the library's offline driver (no DDS); the
// live mode (publish topology/state, subscribe strokes) joins the DDS pipeline.
#include "tachi/common/app.hpp"
#include "tachi/sim/object.hpp"
#include "tachi/sim/offline.hpp"
#include "live.hpp"

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
  tachi::sim::LiveOptions live;
  tachi::sim::ObjectOptions object;
  auto* offline_flag = app.add_flag("--offline", offline, "Run without DDS: simulate, then export the mesh and a summary");
  tachi::sim::add_offline_flags(app, options);
  app.get_option("--stroke")->needs(offline_flag);  // live strokes come over DDS
  tachi::sim::add_object_flags(app, object);
  tachi::sim::add_live_flags(app, live);
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(log_level);
  options.object = tachi::sim::load_object(object);
  if (options.object) spdlog::info("tachi-sim: object of {} points", options.object->points().size());

  if (!offline) {
    // Live: strokes come from tachi-filter over DDS; --steps, when given, bounds the run.
    tachi::common::install_stop_handlers();
    const auto steps_given = app.get_option("--steps")->count() > 0 ? std::optional<int>(options.steps) : std::nullopt;
    return tachi::sim::run_live(options, steps_given, live);
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
