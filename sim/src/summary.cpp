#include "tachi/sim/summary.hpp"

#include "tachi/sim/pieces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace tachi::sim {
namespace {

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

/// How far the cut strays from the stroke's path on the cloth, in cells: exact mode measures its cut edges
/// against the segments that made them; grid mode its cut-line particles against the stroke's path; delete
/// mode (no cut edge, holes) reports the grid mode's measure of nothing: 0.
double cut_deviation_cells(const StrokeCutter& cutter) {
  if (const ExactCutter* exact = cutter.exact()) return exact->max_deviation_cells();
  const auto& line = cutter.total().cut_line;
  double worst = 0.0;
  for (const GridCoord g : line) {
    const Eigen::Vector2d p{g.u, g.v};
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& path : cutter.paths()) {
      for (std::size_t i = 0; i + 1 < path.size(); ++i) {
        const Eigen::Vector2d a = path[i].cast<double>();
        const Eigen::Vector2d d = path[i + 1].cast<double>() - a;
        const double s = d.squaredNorm() > 0.0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
        nearest = std::min(nearest, (p - (a + s * d)).norm());
      }
      if (path.size() == 1) nearest = std::min(nearest, (p - path[0].cast<double>()).norm());
    }
    if (std::isfinite(nearest)) worst = std::max(worst, nearest);
  }
  return worst;
}

}  // namespace

nlohmann::json to_json(const Summary& s) {
  nlohmann::json j{
      {"particles", s.particles},   {"springs", s.springs},       {"triangles", s.triangles},
      {"pieces", s.pieces},         {"max_strain", s.max_strain}, {"steps", s.steps},
      {"step_ms_median", s.step_ms_median}, {"step_ms_p95", s.step_ms_p95}, {"step_ms_max", s.step_ms_max},
      {"columns", s.columns},       {"rows", s.rows},
  };
  for (const auto& [key, value] : s.extra.items()) j[key] = value;
  return j;
}

Summary summarize(const Cloth& cloth) {
  Summary s;
  s.particles = cloth.particle_count();
  s.springs = cloth.alive_spring_count();
  s.triangles = cloth.alive_triangle_count();
  const Pieces pieces = find_pieces(cloth);
  s.pieces = pieces.cloth_count();  // pieces of cloth; particles in no triangle are counted apart (pieces.hpp)
  s.extra["loose_particles"] = pieces.loose_particles();
  s.max_strain = cloth.max_structural_strain();
  // Whether max_strain is a cloth at rest or a snapshot of one still moving: the kinetic energy of the pieces a
  // pin holds (pieces that fell off are meant to move).
  double held_kinetic = 0.0;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (pieces.pinned[pieces.piece_of[i]] == 0) continue;
    held_kinetic += 0.5 * static_cast<double>(cloth.mass[i]) * static_cast<double>(cloth.velocity[i].squaredNorm());
  }
  s.extra["held_kinetic_energy_j"] = held_kinetic;
  s.columns = cloth.columns;
  s.rows = cloth.rows;
  return s;
}

void add_session_summary(Summary& summary, const Session& session) {
  summary.extra["blade_force_n"] = session.blade().params().force_n;
  summary.extra["blade_drag_m"] = session.max_drag_m();
  summary.extra["blade_max_contact_force_n"] = session.max_contact_force_n();
  summary.extra["solver"] = std::string{to_string(session.solver_kind())};
  summary.extra["object_points"] = session.object() ? session.object()->points().size() : 0U;
  // Counted where the cuts are made: a stroke that cut nothing is no cut, one still open at the end is.
  summary.extra["strokes"] = session.strokes();
  summary.extra["cuts"] = session.cuts();
  summary.extra["tether_repair_steps"] = session.repair_steps();
  const Cloth& cloth = session.cloth();
  float lowest = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) lowest = std::min(lowest, cloth.position[i].y());
  summary.extra["lowest_y_m"] = cloth.particle_count() > 0 ? lowest : 0.0F;
}

void add_cut_summary(Summary& summary, const Cloth& cloth, const StrokeCutter& cutter) {
  const StrokeReport& cut = cutter.total();
  nlohmann::json cut_line = nlohmann::json::array();
  for (const GridCoord g : cut.cut_line) cut_line.push_back({g.u, g.v});
  summary.extra["fallen_pieces"] = find_pieces(cloth).cloth_fallen();
  summary.extra["cut_particles"] = cut.particles_duplicated;
  summary.extra["cut_length_m"] = cut.cut_length_m;
  summary.extra["cut_line"] = std::move(cut_line);
  summary.extra["cut_lines"] = cut.lines;
  summary.extra["blade"] = std::string{to_string(cutter.options().blade)};
  summary.extra["blade_force_n"] = sharpness(cutter.options().blade).force_n();
  summary.extra["topology_version"] = cloth.topology_version;
  summary.extra["cut_mode"] = std::string{to_string(cutter.options().mode)};
  summary.extra["cut_deviation_cells_max"] = cut_deviation_cells(cutter);
}

void add_step_times(Summary& summary, const std::vector<double>& step_ms) {
  summary.step_ms_median = percentile(step_ms, 0.5);
  summary.step_ms_p95 = percentile(step_ms, 0.95);
  summary.step_ms_max = step_ms.empty() ? 0.0 : *std::max_element(step_ms.begin(), step_ms.end());
}

void add_step_times(Summary& summary, const common::DurationHistogram& step_ms) {
  summary.step_ms_median = step_ms.quantile(0.5);
  summary.step_ms_p95 = step_ms.quantile(0.95);
  summary.step_ms_max = step_ms.max_ms();
}

}  // namespace tachi::sim
