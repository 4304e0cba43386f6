// What a run produced, as summary.json reports it: the cloth's counts and strain, the step times, and what the
// cutting and the session did. The offline and live modes fill the same keys.
#pragma once

#include "tachi/common/latency.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/session.hpp"
#include "tachi/sim/stroke.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <vector>

namespace tachi::sim {

/// What a run produced. Keys of to_json(): the contract plus extras.
struct Summary {
  std::size_t particles = 0;
  std::size_t springs = 0;    ///< live springs
  std::size_t triangles = 0;  ///< live triangles
  std::size_t pieces = 0;     ///< pieces of cloth: components over live springs with a live triangle (pieces.hpp)
  float max_strain = 0.0F;    ///< max over live structural springs of length / rest - 1
  int steps = 0;
  double step_ms_median = 0.0;
  double step_ms_p95 = 0.0;
  double step_ms_max = 0.0;
  int columns = 0;
  int rows = 0;
  nlohmann::json extra = nlohmann::json::object();  ///< further keys merged into to_json()'s output
};

/// Summary as JSON: particles, springs, triangles, pieces, max_strain, steps, step_ms_median, ... + extra.
[[nodiscard]] nlohmann::json to_json(const Summary& summary);

/// Summary of the cloth as it is now (no timing).
[[nodiscard]] Summary summarize(const Cloth& cloth);

/// Adds what the cutting did (fallen_pieces, cut_particles, cut_length_m, cut_line, cut_lines, blade,
/// blade_force_n, topology_version, cut_mode, cut_deviation_cells_max) to a summary; the offline and live
/// modes report the same keys.
void add_cut_summary(Summary& summary, const Cloth& cloth, const StrokeCutter& cutter);
/// Adds what the session layer did (blade_force_n, blade_drag_m, blade_max_contact_force_n, solver,
/// object_points, lowest_y_m) to a summary; the offline and live modes report the same keys.
void add_session_summary(Summary& summary, const Session& session);
/// Sets step_ms_median, step_ms_p95 and step_ms_max from the step times of a run.
void add_step_times(Summary& summary, const std::vector<double>& step_ms);
/// The same from a live run's histogram (its figures within 1 %, its memory constant however long the run).
void add_step_times(Summary& summary, const common::DurationHistogram& step_ms);
}  // namespace tachi::sim
