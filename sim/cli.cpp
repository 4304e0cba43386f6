#include "cli.hpp"

#include "flags.hpp"
#include "tachi/bus/topics.hpp"

#include <spdlog/spdlog.h>

#include <iostream>

namespace tachi::sim {

int parse_flags(int argc, char** argv, Flags& flags) {
  CLI::App app{"tachi-sim: mass-spring cloth simulator (Provot), collisions, grabbing, cutting"};
  app.name("tachi-sim");
  std::string log_level = "info";
  auto* offline_flag = app.add_flag("--offline", flags.offline, "Run without DDS: simulate, then export the mesh and a summary");
  add_offline_flags(app, flags.options);
  app.get_option("--stroke")->needs(offline_flag);  // live strokes come over DDS
  add_object_flags(app, flags.object);
  LiveOptions& live = flags.live;
  common::add_bus_flags(app, flags.bus);
  app.add_option("--cloth-id", live.cloth_id, "Key of this cloth on the bus")->capture_default_str();
  app.add_option("--state-every", live.state_every, "Live: publish the cloth state every Nth step")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--duration", live.duration_s, "Live: stop after this many seconds (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--exit-when-idle", live.exit_when_idle_s,
                 "Live: stop when no hand sample arrived for this many seconds after the first and no hand source (tachi-sensor, "
                 "tachi-filter) is starting again (0: never)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--journal", live.journal,
                 "Live: journal every applied hand sample to FILE; a restarted simulator given the same FILE replays it "
                 "to the same cloth and cuts, then resumes (docs/reliability.md)");
  app.add_option("--hand-radius", live.hand_radius_m, "Live: the idle hand pushes the cloth as a sphere of this radius, m (0: off)")
      ->check(CLI::Range(0.0F, 1.0F));
  common::add_log_level_flag(app, log_level);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  common::set_log_level(log_level);
  const auto& cloth = flags.options.cloth;
  if (!flags.offline && (cloth.columns > bus::topics::kMaxLiveGrid || cloth.rows > bus::topics::kMaxLiveGrid)) {
    std::cerr << "tachi-sim: --grid: the live simulator takes at most " << bus::topics::kMaxLiveGrid << " x "
              << bus::topics::kMaxLiveGrid << " particles (--offline: up to 4096)\n";
    return common::kExitUsage;
  }
  // Live: strokes come from tachi-filter over DDS; --steps, when given, bounds the run.
  if (app.get_option("--steps")->count() > 0) live.max_steps = flags.options.steps;
  flags.options.object = load_object(flags.object);
  if (flags.options.object) spdlog::info("tachi-sim: object of {} points", flags.options.object->points().size());
  return -1;
}

int run_offline_and_report(const OfflineOptions& options) {
  const Summary summary = run_offline(options);
  spdlog::info("{} steps of a {}x{} cloth: max strain {:.4f}, median step {:.3f} ms", summary.steps, summary.columns,
               summary.rows, summary.max_strain, summary.step_ms_median);
  if (options.export_dir.empty()) std::cout << to_json(summary).dump(2) << '\n';
  return common::kExitOk;
}

}  // namespace tachi::sim
