// tachi-sim's live mode: the Session on the DDS bus (strokes in; topology, state and cuts out).
#pragma once

#include "tachi/common/app.hpp"
#include "tachi/sim/offline.hpp"

namespace tachi::sim {

struct LiveOptions {
  common::BusOptions bus;
  std::uint32_t cloth_id = 1;
  int state_every = 1;            ///< publish the cloth state every Nth step
  double duration_s = 0.0;        ///< stop after this long (0: until SIGINT/SIGTERM)
  double exit_when_idle_s = 0.0;  ///< stop when no hand sample arrived for this long after the first (0: never)
  float hand_radius_m = 0.0F;     ///< the idle hand as a collider sphere (0: off)
  std::string journal;            ///< replay then append every applied hand sample here (empty: no journal)
};

void add_live_flags(CLI::App& app, LiveOptions& options);

/// Runs until stopped; then, when `shared.export_dir` is set, writes cloth.obj and summary.json there.
int run_live(const OfflineOptions& shared, std::optional<int> max_steps, const LiveOptions& live);

}  // namespace tachi::sim
