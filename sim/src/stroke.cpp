#include "tachi/sim/stroke.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tachi/common/csv.hpp"

namespace tachi::sim {

std::optional<CutMode> parse_cut_mode(std::string_view name) {
  if (name == "exact") return CutMode::Exact;
  if (name == "grid") return CutMode::Grid;
  if (name == "delete") return CutMode::Delete;
  return std::nullopt;
}

std::string_view to_string(CutMode mode) {
  switch (mode) {
    case CutMode::Exact:
      return "exact";
    case CutMode::Grid:
      return "grid";
    case CutMode::Delete:
      return "delete";
  }
  return "exact";
}

bool stroke_sample_due(double t_s, long long step, double dt_s) {
  return t_s < (static_cast<double>(step) + 0.5) * dt_s;
}

std::size_t drop_impossible_samples(std::vector<StrokeSample>& samples, const common::OutlierParams& params,
                                    double nominal_dt_s) {
  common::HandSpeedLimit limit{params, nominal_dt_s};
  std::size_t dropped = 0;
  std::vector<StrokeSample> kept;
  kept.reserve(samples.size());
  for (const StrokeSample& s : samples) {
    const auto stamp_ns = static_cast<std::int64_t>(std::llround(s.t * 1e9));
    if (limit.check(s.position, stamp_ns) == common::HandSpeedLimit::Verdict::Outlier) {
      ++dropped;
      continue;
    }
    kept.push_back(s);
  }
  samples = std::move(kept);
  return dropped;
}

StrokeFile parse_stroke_csv(std::istream& in) {
  StrokeFile out;
  common::CsvReader csv(in);
  if (csv.header().empty()) {
    out.error = "empty file: expected the header t,x,y,z";
    return out;
  }
  std::vector<std::string> header = csv.header();
  for (auto& name : header)
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  if (header != std::vector<std::string>{"t", "x", "y", "z"}) {
    out.error = "the first line must be the header t,x,y,z";
    return out;
  }
  double last_t = -std::numeric_limits<double>::infinity();
  const auto skip = [&](std::size_t line, const std::string& why) {
    if (out.problems.size() < StrokeFile::kMaxProblems) out.problems.push_back("line " + std::to_string(line) + ": " + why);
    ++out.skipped_rows;
  };
  while (const auto row = csv.next()) {
    const auto& cells = row->cells;
    // Four numbers; a trailing comma has always been let through.
    const bool four = cells.size() == 4 || (cells.size() == 5 && cells[4].empty());
    std::array<std::optional<double>, 4> v;
    for (std::size_t i = 0; four && i < 4; ++i) v[i] = common::to_double(cells[i]);
    if (!four) {
      skip(row->line, "expected 4 fields t,x,y,z, got " + std::to_string(cells.size()));
      continue;
    }
    if (!v[0] || !v[1] || !v[2] || !v[3]) {
      skip(row->line, "not four finite numbers");
      continue;
    }
    // Out of range before out of order: one row with t = 1e30 must not make every later row "go back".
    if (std::abs(*v[0]) > kMaxStrokeTime_s) {
      skip(row->line, "time " + cells[0] + " s is out of range (|t| <= 1e6 s)");
      continue;
    }
    if (std::max({std::abs(*v[1]), std::abs(*v[2]), std::abs(*v[3])}) > kMaxStrokeCoordinate_m) {
      skip(row->line, "position is out of range (|x|, |y|, |z| <= 100 m)");
      continue;
    }
    if (*v[0] < last_t) {
      skip(row->line, "time " + cells[0] + " s goes back (the previous row is at " + std::to_string(last_t) + " s)");
      continue;
    }
    last_t = *v[0];
    out.samples.push_back({*v[0], Eigen::Vector3d{*v[1], *v[2], *v[3]}.cast<float>()});
  }
  if (out.samples.empty()) out.error = "no usable sample after the header";
  return out;
}

namespace {

/// Offset of `point` from particle p in the local frame of the deformed cloth, in grid cells: the frame
/// J = d position / d (u, v) is fitted to p's structural springs by least squares, J = E U^T (U U^T)^-1
/// with E their world vectors and U their rest-coordinate vectors (on the grid: the mean of the springs
/// along u and along v); the flat rest frame where the springs do not span both directions.
struct GridOffset {
  Eigen::Vector2d cells{0.0, 0.0};
  double in_plane_m = 0.0;  ///< the offset's length on the sheet (the frame applied to it), metres
};
GridOffset grid_offset(const Cloth& cloth, std::uint32_t p, const Eigen::Vector3f& point) {
  Eigen::Matrix<double, 3, 2> eu = Eigen::Matrix<double, 3, 2>::Zero();
  Eigen::Matrix2d uu = Eigen::Matrix2d::Zero();
  for (const std::uint32_t k : cloth.springs_of(p)) {
    if (cloth.kind[k] != SpringKind::Structural) continue;
    const std::uint32_t q = cloth.spring_a[k] == p ? cloth.spring_b[k] : cloth.spring_a[k];
    const Eigen::Vector3d e = (cloth.position[q] - cloth.position[p]).cast<double>();
    const Eigen::Vector2d d = (cloth.rest_uv[q] - cloth.rest_uv[p]).cast<double>();
    eu += e * d.transpose();
    uu += d * d.transpose();
  }
  Eigen::Matrix<double, 3, 2> frame;
  frame << cloth.spacing_x(), 0.0, 0.0, -cloth.spacing_y(), 0.0, 0.0;
  if (std::abs(uu.determinant()) > 1e-6 * std::max(uu.squaredNorm(), 1e-12)) frame = eu * uu.inverse();
  const Eigen::Vector3d r = (point - cloth.position[p]).cast<double>();
  const Eigen::Matrix2d m = frame.transpose() * frame;
  if (!(std::abs(m.determinant()) > 1e-6 * m.squaredNorm())) return {};
  const Eigen::Vector2d cells = m.inverse() * (frame.transpose() * r);
  return {cells, (frame * cells).norm()};
}

// The index a track ends at without its last `tail` of length (walked back from its end, in the track's units):
// the current line's last stretch, which a sample going straight on would otherwise be "along".
template <typename Point>
std::size_t end_before_tail(const std::vector<Point>& track, double tail) {
  std::size_t end = track.size();
  double walked = 0.0;
  while (end > 0 && walked < tail) {
    --end;
    if (end > 0) walked += (track[end].template cast<double>() - track[end - 1].template cast<double>()).norm();
  }
  return end;
}

/// The particle nearest to `point`, by looking at every one.
std::uint32_t scan_nearest(const Cloth& cloth, const Eigen::Vector3f& point) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions must be packed x, y, z");
  // A plain float loop over the interleaved coordinates, which the compiler vectorises.
  const float* xyz = cloth.position.front().data();
  const float px = point.x();
  const float py = point.y();
  const float pz = point.z();
  std::uint32_t best = 0;
  float d = std::numeric_limits<float>::infinity();
  const std::size_t n = cloth.particle_count();
  for (std::uint32_t i = 0; i < n; ++i) {
    const float dx = xyz[3 * i] - px;
    const float dy = xyz[3 * i + 1] - py;
    const float dz = xyz[3 * i + 2] - pz;
    const float di = dx * dx + dy * dy + dz * dz;
    if (di < d) {
      d = di;
      best = i;
    }
  }
  return best;
}

/// The closest points of segments p1-p2 and q1-q2 and their distance (Ericson 2005, "Real-Time Collision
/// Detection", section 5.1.9).
struct SegmentMeeting {
  Eigen::Vector2d on_first;
  Eigen::Vector2d on_second;
  double distance;
};
SegmentMeeting closest_points(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                              const Eigen::Vector2d& q2) {
  const Eigen::Vector2d d1 = p2 - p1;
  const Eigen::Vector2d d2 = q2 - q1;
  const Eigen::Vector2d r = p1 - q1;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  double s = 0.0;
  double t = 0.0;
  constexpr double kTiny = 1e-18;
  if (a <= kTiny && e <= kTiny) {
    s = t = 0.0;
  } else if (a <= kTiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denominator = a * e - b * b;
      s = denominator > kTiny ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  const Eigen::Vector2d on_first = p1 + s * d1;
  const Eigen::Vector2d on_second = q1 + t * d2;
  return {on_first, on_second, (on_first - on_second).norm()};
}

/// Whether the edge between rest points a and b lies on one side of the grid rectangle: an edge of the cloth
/// itself, not of a cut.
bool on_same_border(const Cloth& cloth, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  constexpr float kOn = 1e-4F;
  const auto col = static_cast<float>(cloth.columns - 1);
  const auto row = static_cast<float>(cloth.rows - 1);
  return (std::abs(a.x()) < kOn && std::abs(b.x()) < kOn) || (std::abs(a.y()) < kOn && std::abs(b.y()) < kOn) ||
         (std::abs(a.x() - col) < kOn && std::abs(b.x() - col) < kOn) ||
         (std::abs(a.y() - row) < kOn && std::abs(b.y() - row) < kOn);
}

/// The live triangle other than `t` with both particles a and b, if any (none across a cut or the cloth's edge).
std::optional<std::uint32_t> across(const Cloth& cloth, std::uint32_t t, std::uint32_t a, std::uint32_t b) {
  for (const std::uint32_t k : cloth.triangles_of(a)) {
    if (k == t) continue;
    const auto& v = cloth.triangles[k];
    if (v[0] == b || v[1] == b || v[2] == b) return k;
  }
  return std::nullopt;
}

/// The straight rest-coordinate walk from particle p towards `target` over the triangles it crosses (a few:
/// the offset from the nearest particle is about a cell). It ends at `target` if the walk stays on the cloth or
/// leaves it across the cloth's own edge (a hand beyond the edge keeps its (u, v) outside the rectangle, which
/// clips a stroke there); otherwise where it first leaves the cloth through a cut, with the particles of that
/// cut edge (both p where the walk leaves p's own triangles at once). If the walk meets a vertex or an edge it
/// cannot decide, `target` as it was.
struct Walk {
  Eigen::Vector2d uv;
  std::optional<std::array<std::uint32_t, 2>> cut;
};
Walk walk_to(const Cloth& cloth, std::uint32_t p, const Eigen::Vector2d& target) {
  const Eigen::Vector2d start = cloth.rest_uv[p].cast<double>();
  const Eigen::Vector2d d = target - start;
  if (d.squaredNorm() < 1e-12 || cloth.triangles_of(p).empty()) return {target, std::nullopt};
  const auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  const auto uv = [&](std::uint32_t i) { return Eigen::Vector2d{cloth.rest_uv[i].cast<double>()}; };
  constexpr double kEps = 1e-9;
  // The triangle at p whose corner holds the direction d (d = alpha (q - p) + beta (r - p), both >= 0).
  std::optional<std::uint32_t> tri;
  std::uint32_t a = 0;
  std::uint32_t b = 0;
  double s = 0.0;  // how far along start -> target the walk has come
  for (const std::uint32_t t : cloth.triangles_of(p)) {
    const auto& v = cloth.triangles[t];
    const std::uint32_t q = v[0] == p ? v[1] : v[0];
    const std::uint32_t r = v[2] == p ? v[1] : v[2];
    const Eigen::Vector2d e1 = uv(q) - start;
    const Eigen::Vector2d e2 = uv(r) - start;
    const double det = cross(e1, e2);
    if (std::abs(det) < kEps) continue;
    const double alpha = cross(d, e2) / det;
    const double beta = cross(e1, d) / det;
    if (alpha < -kEps || beta < -kEps) continue;
    if (alpha + beta <= 1.0) return {target, std::nullopt};  // inside p's own triangle
    tri = t;
    a = q;
    b = r;
    s = 1.0 / (alpha + beta);
    break;
  }
  if (!tri) {
    // d points out of p's fan at once: into a cut's gap at p, or out over the cloth's edge.
    const bool beyond_edge = target.x() < 0.0 || target.y() < 0.0 || target.x() > cloth.columns - 1 ||
                             target.y() > cloth.rows - 1;
    if (beyond_edge) return {target, std::nullopt};
    // On the cut: the nearest point of p's edges that no other triangle shares (its lip).
    Eigen::Vector2d on = start;
    double nearest = std::numeric_limits<double>::infinity();
    for (const std::uint32_t t : cloth.triangles_of(p)) {
      for (const std::uint32_t q : cloth.triangles[t]) {
        if (q == p || across(cloth, t, p, q)) continue;
        const auto meet = closest_points(target, target, start, uv(q));
        if (meet.distance < nearest) {
          nearest = meet.distance;
          on = meet.on_second;
        }
      }
    }
    return {on, std::array<std::uint32_t, 2>{p, p}};
  }
  for (int steps = 0; steps < 64; ++steps) {
    // The walk crosses edge (a, b) of *tri at start + s d.
    const auto next = across(cloth, *tri, a, b);
    if (!next) {
      if (on_same_border(cloth, cloth.rest_uv[a], cloth.rest_uv[b])) return {target, std::nullopt};
      return {start + s * d, std::array<std::uint32_t, 2>{a, b}};
    }
    const auto& v = cloth.triangles[*next];
    const std::uint32_t o = v[0] != a && v[0] != b ? v[0] : (v[1] != a && v[1] != b ? v[1] : v[2]);
    // Leaves *next through (a, o) or (b, o) further along, or ends inside it.
    double best = 2.0;
    std::uint32_t keep = 0;
    for (const std::uint32_t w : {a, b}) {
      const Eigen::Vector2d e = uv(o) - uv(w);
      const double den = cross(d, e);
      if (std::abs(den) < kEps) continue;
      const double t = cross(uv(w) - start, e) / den;  // along start -> target
      const double u = cross(uv(w) - start, d) / den;  // along w -> o
      if (t > s + kEps && u >= -kEps && u <= 1.0 + kEps && t < best) {
        best = t;
        keep = w;
      }
    }
    if (best >= 1.0) return {target, std::nullopt};  // ends in *next (or the walk lost its way: as it was)
    tri = *next;
    a = keep;
    b = o;
    s = best;
  }
  return {target, std::nullopt};
}

/// How much farther from the cut the other lip may put a point than this one did, cells (their frames differ).
constexpr double kLipSlackCells = 0.5;

/// Where `point`, `uv` from particle p's frame, is on the cloth in rest coordinates, given the cuts. If the walk
/// from p to uv crosses a cut, the point is over the other lip's material (a still cloth: both lips in one
/// place, and p is just the copy on this side) or over the gap between the opened lips. Seen from the other lip
/// (a copy of the cut edge's particles) the first has it on its own triangles: that is its (u, v). In the gap
/// neither has: a point there is extrapolated from one lip's frame beside the cut by up to half the gap, onto
/// the other's material (a hanging cloth's cut opens by centimetres, a cell and more), but in rest coordinates
/// the two lips are one place, the cut itself, and that is where the point is.
Eigen::Vector2d onto_lip(const Cloth& cloth, std::uint32_t p, const Eigen::Vector3f& point, const Eigen::Vector2d& uv) {
  const Walk walk = walk_to(cloth, p, uv);
  if (!walk.cut) return uv;
  // The other lip's copies of a cut edge's particle share its rest coordinate. Only particles a cut appended
  // (past the grid's) and the grid particle at that coordinate can: a grid particle's rest coordinate is its
  // (u, v) and never changes. Scanning every particle cost a 256 x 256 cloth 65k reads a sample over a cut.
  const auto grid_particles = static_cast<std::uint32_t>(cloth.columns * cloth.rows);
  const auto n = static_cast<std::uint32_t>(cloth.particle_count());
  for (const std::uint32_t end : *walk.cut) {
    const Eigen::Vector2f at = cloth.rest_uv[end];
    const auto other_lip = [&](std::uint32_t q) -> std::optional<Eigen::Vector2d> {
      if (q == end || cloth.rest_uv[q] != at || cloth.triangles_of(q).empty()) return std::nullopt;
      const Eigen::Vector2d from_q = cloth.rest_uv[q].cast<double>() + grid_offset(cloth, q, point).cells;
      // Beside the cut: what p put across it by a fraction of a cell, the other lip has on its side by as much.
      const bool beside = (from_q - walk.uv).norm() <= (uv - walk.uv).norm() + kLipSlackCells;
      if (beside && !walk_to(cloth, q, from_q).cut) return from_q;
      return std::nullopt;
    };
    const bool on_grid_point = at.x() == std::floor(at.x()) && at.y() == std::floor(at.y()) && at.x() >= 0.0F &&
                               at.y() >= 0.0F && at.x() < static_cast<float>(cloth.columns) &&
                               at.y() < static_cast<float>(cloth.rows);
    if (on_grid_point) {
      if (const auto found = other_lip(cloth.index(static_cast<int>(at.x()), static_cast<int>(at.y())))) return *found;
    }
    for (std::uint32_t q = grid_particles; q < n; ++q) {
      if (const auto found = other_lip(q)) return *found;
    }
  }
  return walk.uv;
}

}  // namespace

ClothPoint ClothLocator::locate(const Cloth& cloth, const Eigen::Vector3f& point) {
  ClothPoint out;
  const std::size_t n = cloth.particle_count();
  if (n == 0) return out;
  const auto distance2 = [&](std::uint32_t i) { return (cloth.position[i] - point).squaredNorm(); };
  if (!hint_ || *hint_ >= n) {
    // No previous answer: start where the point would be on the flat, uncut grid.
    const float u = (point.x() - cloth.position[0].x()) / cloth.spacing_x();
    const float v = (cloth.position[0].y() - point.y()) / cloth.spacing_y();
    const int gu = std::isfinite(u) ? static_cast<int>(std::clamp(u, 0.0F, static_cast<float>(cloth.columns - 1)) + 0.5F) : 0;
    const int gv = std::isfinite(v) ? static_cast<int>(std::clamp(v, 0.0F, static_cast<float>(cloth.rows - 1)) + 0.5F) : 0;
    hint_ = cloth.index(gu, gv);
  }
  // Greedy descent over live springs from the previous answer (a hand moves little between samples).
  std::uint32_t p = *hint_;
  float dp = distance2(p);
  for (bool improved = true; improved;) {
    improved = false;
    const std::uint32_t from = p;
    for (const std::uint32_t k : cloth.springs_of(from)) {
      const std::uint32_t q = cloth.spring_a[k] == from ? cloth.spring_b[k] : cloth.spring_a[k];
      const float dq = distance2(q);
      if (dq < dp) {
        p = q;
        dp = dq;
        improved = true;
      }
    }
  }
  // The descent's minimum is the nearest particle when the point projects onto the sheet next to it (the
  // hand may be centimetres in front of the cloth). Otherwise (off the edge, a fold, a piece cut off between
  // the hint and the hand) look at every particle.
  // Within a cell in the particle's own frame is not enough where that frame is stretched (a lip of an opened
  // cut, pulled wide: the descent, which cannot cross the cut, stops on it), so the offset must also be within a
  // cell on the sheet, in metres.
  const double cell_m = std::max(cloth.spacing_x(), cloth.spacing_y());
  GridOffset offset = grid_offset(cloth, p, point);
  if (!(std::abs(offset.cells.x()) <= 1.0 && std::abs(offset.cells.y()) <= 1.0 && offset.in_plane_m <= cell_m)) {
    const std::uint32_t scanned = scan_nearest(cloth, point);
    if (scanned != p) {
      p = scanned;
      offset = grid_offset(cloth, p, point);
    }
  }
  hint_ = p;
  out.particle = p;
  out.grid = cloth.grid[p];
  out.distance_m = std::sqrt(distance2(p));
  out.uv = cloth.rest_uv[p].cast<double>() + offset.cells;
  if (lips_meet_) out.uv = onto_lip(cloth, p, point, out.uv);
  out.inside = out.uv.x() >= -margin_ && out.uv.y() >= -margin_ && out.uv.x() <= cloth.columns - 1 + margin_ &&
               out.uv.y() <= cloth.rows - 1 + margin_;
  return out;
}

StrokeCutter::StrokeCutter(Cloth& cloth, StrokeOptions options)
    : cloth_(&cloth), options_(options), cutter_(cloth),
      locator_(options.inside_margin_cells, options.mode != CutMode::Delete), backtrack_cells_(options.tolerance_cells) {
  if (follows_path()) {
    exact_.emplace(cloth);
    options_.tolerance_cells = options_.exact_tolerance_cells;
    backtrack_cells_ = options_.exact_backtrack_cells;
  }
}

TopologyChange StrokeCutter::begin_stroke() {
  TopologyChange change = end_stroke();
  open_ = true;
  report_ = {};
  previous_.reset();
  pending_.clear();
  line_.reset();
  return change;
}

GridCoord StrokeCutter::boundary_point(const Eigen::Vector2d& uv) const {
  // Clamped before rounding: a hand metres away must not overflow the conversion.
  const double u = std::clamp(uv.x(), 0.0, static_cast<double>(cloth_->columns - 1));
  const double v = std::clamp(uv.y(), 0.0, static_cast<double>(cloth_->rows - 1));
  return {static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))};
}

GridCoord StrokeCutter::grid_point(const Eigen::Vector2d& uv) const {
  GridCoord g = boundary_point(uv);
  if (!previous_) return g;
  const GridCoord last = previous_->grid;
  const double keep = 0.5 + options_.grid_hysteresis_cells;
  const Eigen::Vector2d on = clamp_uv(uv);
  if (std::abs(on.x() - last.u) <= keep) g.u = last.u;
  if (std::abs(on.y() - last.v) <= keep) g.v = last.v;
  return g;
}

Eigen::Vector2d StrokeCutter::clamp_uv(const Eigen::Vector2d& uv) const {
  return {std::clamp(uv.x(), 0.0, static_cast<double>(cloth_->columns - 1)),
          std::clamp(uv.y(), 0.0, static_cast<double>(cloth_->rows - 1))};
}

void StrokeCutter::commit(GridCoord g, const Eigen::Vector2d& uv, const Eigen::Vector3f& direction,
                          TopologyChange& change) {
  // The stroke's path on the cloth as the cut took it, in every mode (pattern.svg, cut_deviation_cells_max).
  const Eigen::Vector2d to = clamp_uv(uv);
  // A hand slowing down at the end of a stroke wobbles around one spot; along the path that is a small
  // knot, and each of its loops would cut out an island (the straight_cut recording: 3-10 pieces instead
  // of one slit). Such a point does not join the cut; the next one goes on from where the cut ends.
  // A segment wholly along cuts already made cuts nothing and closes no loop: the hand going back over its cut
  // runs along its own path, and its way back "closed" a loop with the cut just made at every commit, so the
  // cut's end stayed at the turn and a later pass never cut the stretch the first pass left uncut there. In exact
  // mode too (since session 42): the end stayed at the turn until a point lay far enough off to close no small
  // loop, and the chord from the turn to it cut a corner off the bends between (development stroke 565).
  if (follows_path() && path_end_ && closes_small_loop(*path_end_, to) &&
      ((to - *path_end_).norm() <= 1e-9 || !recut_parts(*path_end_, to, direction).empty())) {
    return;
  }
  // For the same reason a step shorter than the wobble does not join the cut either, unless it reaches the
  // cloth's edge (a cut across the cloth must get there to separate it) or ends a stroke that has cut (the cut
  // reaches the stroke's end point; a pass going back over the cut would otherwise cut that last step then).
  // A stroke that only wobbled where the blade entered cuts nothing: its end is no cut either.
  if (follows_path() && path_end_) {
    const bool on_edge = to.x() <= 0.0 || to.y() <= 0.0 || to.x() >= cloth_->columns - 1 || to.y() >= cloth_->rows - 1;
    const bool ends_a_cut = ending_ && !paths_.empty() && paths_.back().size() >= 2;
    const double min_step = at_least(options_.exact_min_step_cells, options_.exact_min_step_m);
    if (!on_edge && !ends_a_cut && (to - *path_end_).norm() < min_step) return;
  }
  const bool moved = !path_end_ || (to - *path_end_).norm() > 1e-9;
  if (!path_end_) {
    paths_.emplace_back();
    path_cuts_.clear();
  }
  if (moved) {
    paths_.back().push_back(to.cast<float>());
    path_cuts_.push_back(0);
  }
  const std::optional<Eigen::Vector2d> from = path_end_;
  path_end_ = to;
  if (!from) {
    tracks_.emplace_back();
    track_boxes_.emplace_back();  // empty
    blade_tracks_.emplace_back();
    blade_uvs_.emplace_back();
    blade_boxes_.emplace_back();
    extend_track(to.cast<float>());
    recent_.clear();
    recent_hands_.clear();
    arrived_on_cut_ = true;
  }
  // Where the segment runs along a cut already made it does not cut again (recut_parts); the samples up to
  // here then join the cut's track.
  const auto parts = from && moved ? recut_parts(*from, to, direction) : std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>{};
  if (from && moved) {
    // Whether this segment ends along a cut (the next one then goes on along it).
    arrived_on_cut_ = parts.empty() || (parts.back().second - to).norm() > 1e-9;
    path_cuts_.back() = parts.empty() ? 0 : 1;
    // Only the samples this segment was cut along (within the going-over reach of it) join the track. Where the
    // hand turned back, the samples out to the turn were never cut along: the chord fit commits the sample
    // before the one that no longer fits, on the way back, so up to max_lag_cells at the turn stay uncut. Kept
    // in the track, they made a later pass over that stretch count as going over a cut, and it never cut
    // what the stroke ending there cuts (delete mode: the removed triangles' crumbs at the turn). Delete mode
    // only, with the two small-loop exemptions below: in exact and grid modes the stretch left at a turn is a
    // slit a little shorter (no piece more or fewer), while the later pass that cuts it joins a new part onto
    // the slit's end (exact: a particle and a triangle more at the joint), and through the offline driver
    // exact mode differed on more strokes with them (razor re-cut, seeds 1-300: 32 -> 34 of 300).
    const double reach = kRecutCells + options_.tolerance_cells;
    for (std::size_t i = 0; i < recent_.size(); ++i) {
      const Eigen::Vector2d s = recent_[i].cast<double>();
      if (options_.mode != CutMode::Delete || closest_points(s, s, *from, to).distance <= reach) {
        extend_track(recent_[i]);
        extend_blade_track(recent_hands_[i], recent_[i].cast<double>());
      }
    }
    extend_track(to.cast<float>());
    recent_.clear();
    recent_hands_.clear();
  }
  if (follows_path()) {
    if (!from) {
      ++report_.lines;
      ++total_.lines;
    }
    // The grid points nearest the path, for readers of cut_line (CutEvent, summary) in every mode.
    const GridCoord nearest = boundary_point(to);
    for (StrokeReport* r : {&report_, &total_}) {
      if (!from || r->cut_line.empty() || !(r->cut_line.back() == nearest)) r->cut_line.push_back(nearest);
    }
    if (!from || !moved) return;
    // The cut goes straight from where it ended to this point of the stroke, on the stroke's own path.
    for (const auto& [a, b] : parts) {
      const TopologyChange cut = options_.mode == CutMode::Exact ? exact_->cut(a, b) : exact_->remove_crossed(a, b);
      cutter_.refresh_copies();
      const std::array<GridCoord, 2> ends{boundary_point(a), boundary_point(b)};
      apply_blade_drag(*cloth_, cutter_, ends, direction, options_.blade, options_.drag, drag_scratch_);
      report_.particles_duplicated += cut.duplicated_from.size();
      total_.particles_duplicated += cut.duplicated_from.size();
      const auto length = static_cast<float>(
          std::hypot((b.x() - a.x()) * cloth_->spacing_x(), (b.y() - a.y()) * cloth_->spacing_y()));
      report_.cut_length_m += length;
      total_.cut_length_m += length;
      line_changed_ = line_changed_ || !cut.empty();
      change.merge(cut);
    }
    return;
  }
  double kept_cells = 0.0;
  for (const auto& [a, b] : parts) kept_cells += (b - a).norm();
  if (from && moved && kept_cells < kRecutMinRunCells && (to - *from).norm() >= kRecutMinRunCells) {
    // Grid mode, the segment along an earlier cut but for less than a cell: its staircase, rasterised from
    // other grid points, would cut a second one beside the first. The line ends here and a new one starts
    // at this point.
    add_line_to_report(line_->finish());
    line_.emplace(cloth_->columns, cloth_->rows);
    static_cast<void>(line_->append(g));
    return;
  }
  const auto added = line_->append(g);
  if (added.size() < 2) return;
  // The line's last particles before this run may begin a stretch along a cut too (the run before cut a step
  // off the cut; this one would close the ring).
  const auto& whole = line_->line();
  const std::size_t back = std::min(kGridLookBack, whole.size() - added.size());
  std::vector<GridCoord> rest(whole.end() - static_cast<std::ptrdiff_t>(added.size() + back), whole.end());
  std::size_t first = back;  // rest[first] is where the uncut part begins
  while (rest.size() >= 2) {
    const auto along = along_cut_made(rest, first);
    const std::size_t end = along ? std::max(along->first, first) : rest.size() - 1;
    if (end > first) {
      const std::span<const GridCoord> piece{rest.data() + first, end - first + 1};
      const TopologyChange cut = cutter_.cut(piece);
      apply_blade_drag(*cloth_, cutter_, piece, direction, options_.blade, options_.drag, drag_scratch_);
      report_.particles_duplicated += cut.duplicated_from.size();
      total_.particles_duplicated += cut.duplicated_from.size();
      line_changed_ = line_changed_ || !cut.empty();
      change.merge(cut);
    }
    if (!along) break;
    // Along a cut already made from rest[end] to rest[j]: the line ends at rest[end] and a new one goes on from
    // rest[j] over the same particles (appended one by one, so not rasterised again).
    const std::size_t j = along->second;
    line_->drop_last(rest.size() - 1 - end);
    add_line_to_report(line_->finish());
    line_.emplace(cloth_->columns, cloth_->rows);
    for (std::size_t k = j; k < rest.size(); ++k) static_cast<void>(line_->append(rest[k]));
    rest = line_->line();  // as the builder keeps it (its rules at the cloth's edge)
    first = 0;
  }
}

std::optional<std::pair<std::size_t, std::size_t>> StrokeCutter::along_cut_made(std::span<const GridCoord> run,
                                                                                std::size_t first) const {
  // Two staircases of the same line, rasterised from different grid points (a pass back over a cut starts its
  // line where the hand came back onto the cloth, and seed 000's eqs. (1)-(4) step column first from there),
  // take opposite sides of the cells the line crosses diagonally: together they ring those cells, and each
  // ringed cell fell as a piece (the razor re-cut in grid mode: 3 of the 7 development strokes of 1-300 that
  // differed, each by one cell). A pass back along a cut whose flap swung since lands a cell beside it and cuts
  // off a strip one cell wide (one more of the 7). Where the new staircase goes from a particle on a cut to
  // another that the cuts already join by a path lying within one cell of it (and it within one cell of that
  // path: only slivers narrower than the grid's resolution between them), it is the same line at the grid's
  // resolution: the line follows the cut already made there, which changes nothing.
  // The cloth's edge parts it as a cut does: a staircase a cell inside the edge, joined to a cut, rings cells too
  // (one more of the 7). A single step from one cut particle to another a cell beside the cut rings the cell between
  // as well (a line starting on a cut, where a blade came back to it).
  const auto on_cut = [&](GridCoord g) {
    return on_boundary(g, cloth_->columns, cloth_->rows) || cutter_.edge_cut(g, {g.u + 1, g.v}) ||
           cutter_.edge_cut(g, {g.u - 1, g.v}) || cutter_.edge_cut(g, {g.u, g.v + 1}) ||
           cutter_.edge_cut(g, {g.u, g.v - 1});
  };
  for (std::size_t i = 0; i + 1 < run.size(); ++i) {
    if (!on_cut(run[i])) continue;
    for (std::size_t j = run.size() - 1; j >= std::max(i + 1, first + 1); --j) {
      if (on_cut(run[j]) && cut_path_beside(run.subspan(i, j - i + 1))) return std::pair{i, j};
    }
  }
  return std::nullopt;
}

bool StrokeCutter::cut_path_beside(std::span<const GridCoord> run) const {
  // Breadth first along cut edges and the cloth's edge, through the particles within one cell of `run` (in a box
  // around it).
  const GridCoord from = run.front();
  const GridCoord to = run.back();
  int u0 = from.u, u1 = from.u, v0 = from.v, v1 = from.v;
  for (const GridCoord g : run) {
    u0 = std::min(u0, g.u - 1), u1 = std::max(u1, g.u + 1), v0 = std::min(v0, g.v - 1), v1 = std::max(v1, g.v + 1);
  }
  const int width = u1 - u0 + 1;
  const auto index = [&](GridCoord g) { return static_cast<std::size_t>((g.v - v0) * width + (g.u - u0)); };
  const auto within_one = [](std::span<const GridCoord> of, GridCoord g) {
    return std::any_of(of.begin(), of.end(),
                       [&](GridCoord r) { return std::abs(r.u - g.u) <= 1 && std::abs(r.v - g.v) <= 1; });
  };
  constexpr std::size_t kUnseen = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> came_from(static_cast<std::size_t>(width * (v1 - v0 + 1)), kUnseen);
  std::vector<GridCoord> queue{from};
  came_from[index(from)] = index(from);
  for (std::size_t head = 0; head < queue.size() && came_from[index(to)] == kUnseen; ++head) {
    const GridCoord g = queue[head];
    for (const GridCoord h : {GridCoord{g.u + 1, g.v}, GridCoord{g.u - 1, g.v}, GridCoord{g.u, g.v + 1},
                              GridCoord{g.u, g.v - 1}}) {
      if (h.u < u0 || h.u > u1 || h.v < v0 || h.v > v1 || came_from[index(h)] != kUnseen) continue;
      if (!within_one(run, h)) continue;
      if (!cutter_.edge_cut(g, h) && !boundary_edge(g, h, cloth_->columns, cloth_->rows)) continue;
      came_from[index(h)] = index(g);
      queue.push_back(h);
    }
  }
  if (came_from[index(to)] == kUnseen) return false;
  // The path, walked back from `to` (its order does not matter here).
  std::vector<GridCoord> path{to};
  while (!(path.back() == from)) {
    const std::size_t k = came_from[index(path.back())];
    path.push_back({u0 + static_cast<int>(k % static_cast<std::size_t>(width)),
                    v0 + static_cast<int>(k / static_cast<std::size_t>(width))});
  }
  // Both ways: every particle of the run within one cell of the path too (only slivers lie between them).
  return std::all_of(run.begin(), run.end(), [&](GridCoord g) { return within_one(path, g); });
}

void StrokeCutter::extend_track(const Eigen::Vector2f& sample) {
  tracks_.back().push_back(sample);
  track_boxes_.back().extend(sample);
}

void StrokeCutter::extend_blade_track(const Eigen::Vector3f& hand, const Eigen::Vector2d& uv) {
  blade_tracks_.back().push_back(hand);
  blade_uvs_.back().push_back(clamp_uv(uv).cast<float>());
  blade_boxes_.back().extend(hand);
}

StrokeCutter::BladeTrackHit StrokeCutter::near_blade_track(const Eigen::Vector3f& hand, const Eigen::Vector3f& motion,
                                                           double radius_m, double tail_m) const {
  // The nearest point of the hand paths within the radius, and where the blade was on the cloth then: the segment's
  // two samples' uv, interpolated as the hand's point is between them.
  double best_earlier = std::numeric_limits<double>::infinity();
  double best_turn = std::numeric_limits<double>::infinity();
  Eigen::Vector2d uv_earlier = Eigen::Vector2d::Zero();
  Eigen::Vector2d uv_turn = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < blade_tracks_.size(); ++i) {
    if (static_cast<double>(blade_boxes_[i].exteriorDistance(hand)) > radius_m + 1e-6) continue;
    const auto& track = blade_tracks_[i];
    const auto& uvs = blade_uvs_[i];
    // As near_track: the current line's last stretch is the hand going on, not coming back; unless the hand
    // moves against it (a stroke that turns back along itself).
    const std::size_t end = i + 1 == blade_tracks_.size() && line_ ? end_before_tail(track, tail_m) : track.size();
    for (std::size_t k = 0; k < track.size(); ++k) {
      const bool tail = k >= end;
      double distance = static_cast<double>((track[k] - hand).norm());
      Eigen::Vector2d at = uvs[k].cast<double>();
      if (k > 0) {
        const Eigen::Vector3f d = track[k] - track[k - 1];
        const float len2 = d.squaredNorm();
        if (tail && !(motion.dot(d) < 0.0F)) continue;
        if (len2 > 0.0F) {
          const float t = std::clamp((hand - track[k - 1]).dot(d) / len2, 0.0F, 1.0F);
          const double along = static_cast<double>((track[k - 1] + t * d - hand).norm());
          if (along < distance) {
            distance = along;
            at = ((1.0F - t) * uvs[k - 1] + t * uvs[k]).cast<double>();
          }
        }
      } else if (tail) {
        continue;
      }
      if (distance > radius_m) continue;
      double& best = tail ? best_turn : best_earlier;
      if (distance < best) {
        best = distance;
        (tail ? uv_turn : uv_earlier) = at;
      }
    }
  }
  if (best_earlier <= radius_m) return {BladeTrackMatch::Earlier, uv_earlier};
  if (best_turn <= radius_m) return {BladeTrackMatch::TurnedBack, uv_turn};
  return {};
}

Eigen::Vector2d StrokeCutter::edge_in_slit(const Eigen::Vector2d& at_edge) const {
  // The sample beyond the edge is located by extrapolating the nearest particle's frame, off a flap that moved
  // since the cut was made: the crossing between it and a sample in the slit came down 0.4-1.5 cells from where
  // the cut meets the edge, and the step to it cut a sliver off the lip.
  if (!near_track(at_edge, kSlitCells, kSlitTailCells)) return at_edge;
  return nearest_on_cut(at_edge);
}

Eigen::Vector2d StrokeCutter::in_slit(const Eigen::Vector2d& uv, const Eigen::Vector3f& hand,
                                      const Eigen::Vector3f& motion) const {
  // A blade that goes back along a cut it made rides in the slit: the lips part around it. Located on the
  // cloth as it is now, though, the hand's (u, v) lands on whatever material has moved under it since: the
  // hanging cloth's cut opens and its flaps swing by centimetres, so a pass back along the same hand path came
  // down 0.4-1.2 cells beside the cut, on fresh cloth, and cut slivers (docs/cutting.md, section 10). The hand
  // coming back within kRecutCells of where it was while it cut (in metres on the cloth: two passes of a hand
  // over the same place) onto material within kSlitCells of that cut is in the slit, and its point is the cut's:
  // where the blade cut when the hand was at the nearest point of its earlier path (near_blade_track). The cut's
  // point nearest the material under it instead slid along the cut with the swinging flap (or to the cut's end,
  // where the flap had swung beyond the cloth's edge), and the chords between such points cut corners off the lip.
  // A hand that turns back along the line it is cutting is back in its slit from the turn on (the current line's
  // last stretch counts then, for the hand and for the material).
  const double cell_m = std::min(cloth_->spacing_x(), cloth_->spacing_y());
  if (blade_tracks_.empty()) return uv;
  const BladeTrackHit hit = near_blade_track(hand, motion, kRecutCells * cell_m, kSlitTailCells * cell_m);
  if (hit.match == BladeTrackMatch::None) return uv;
  if (!near_track(uv, kSlitCells, hit.match == BladeTrackMatch::TurnedBack ? 0.0 : kSlitTailCells)) return uv;
  return nearest_on_cut(hit.uv);
}

bool StrokeCutter::near_track(const Eigen::Vector2d& p, double radius, double tail_cells,
                              const Eigen::Vector2d& against) const {
  const Eigen::Vector2f pf = p.cast<float>();
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    // A track whose box is farther than the radius has no sample near enough (the box holds every segment).
    if (static_cast<double>(track_boxes_[i].exteriorDistance(pf)) > radius + 1e-4) continue;
    const auto& track = tracks_[i];
    // The current line's track ends where the segment being cut starts; its last `tail_cells` are left out,
    // or a segment going straight on would be "along" the track it continues. Between lines the last track
    // is a finished cut like any other: a hand back on the cloth where it left it is back in its slit.
    const std::size_t end = i + 1 == tracks_.size() && line_ ? end_before_tail(track, tail_cells) : track.size();
    if (end == 1 && (track[0].cast<double>() - p).norm() <= radius) return true;
    for (std::size_t k = 1; k < end; ++k) {
      if (closest_points(p, p, track[k - 1].cast<double>(), track[k].cast<double>()).distance <= radius) return true;
    }
    // That last stretch, where the path runs back against it (near_blade_track's turn, in rest coordinates).
    for (std::size_t k = std::max<std::size_t>(end, 1); k < track.size(); ++k) {
      const Eigen::Vector2d a = track[k - 1].cast<double>();
      const Eigen::Vector2d b = track[k].cast<double>();
      if (against.dot(b - a) < 0.0 && closest_points(p, p, a, b).distance <= radius) return true;
    }
  }
  return false;
}

Eigen::Vector2d StrokeCutter::nearest_on_cut(const Eigen::Vector2d& p, bool cutting) const {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d at = p;
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    const auto& path = paths_[i];
    // While a segment is being cut (recut_parts), the current path's last point is its end (just recorded):
    // leave it out. Otherwise the last segment is cut already, as much as the others: a hand back on the cloth
    // where it left it lands on it, and so does one turning back along the line it is cutting.
    const std::size_t end = i + 1 == paths_.size() && cutting && line_ ? path.size() - 1 : path.size();
    for (std::size_t k = 1; k < end; ++k) {
      const auto meet = closest_points(p, p, path[k - 1].cast<double>(), path[k].cast<double>());
      if (meet.distance < best) {
        best = meet.distance;
        at = meet.on_second;
      }
    }
  }
  return at;
}

std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> StrokeCutter::recut_parts(const Eigen::Vector2d& from,
                                                                                   const Eigen::Vector2d& to,
                                                                                   const Eigen::Vector3f& direction) const {
  // Going over a cut again must change nothing: cutting a second time a few tenths of a cell beside the
  // first cut out slivers (exact) or deleted a second row of triangles (delete). Two passes of the hand over
  // the same place give samples within kRecutCells of each other, but the simplified paths cut along them
  // each lie up to tolerance_cells off their samples, so the segment is compared with the samples of the
  // cut so far (tracks_), within kRecutCells + tolerance_cells. It is sampled every kRecutStepCells; a run
  // of samples near the track at least kRecutMinRunCells long runs along the cut and is not cut again (a
  // shorter segment is cut: the last step to a stroke's end point must reach it). A shorter run is where the segment leaves or crosses a cut, and is cut through (a
  // crossing must separate). Where a kept part meets a skipped run it starts (ends) on the earlier cut
  // itself, at its nearest point, so the cuts join.
  const Eigen::Vector2d d = to - from;
  const double length = d.norm();
  const int n = std::max(1, static_cast<int>(std::ceil(length / kRecutStepCells)));
  const double near = kRecutCells + options_.tolerance_cells;
  const auto at = [&](int i) -> Eigen::Vector2d { return from + (static_cast<double>(i) / n) * d; };
  // A hand that turned back along the line it is cutting runs along that line's last stretch too: left out, the
  // way back from the turn cut again beside the cut for as long as that stretch (exact: a sliver at the turn). The
  // hand decides that it turned (its motion against its last stretch of path, as near_blade_track), not the
  // points on the cloth: a worn blade drags the cloth where it enters, and the points located on it step back
  // along the line it is beginning while the hand goes on.
  // (No copy of the hand path: a conditional between it and an empty vector would be one.)
  const std::vector<Eigen::Vector3f>* hands = blade_tracks_.empty() ? nullptr : &blade_tracks_.back();
  const bool hand_turned = line_ && hands != nullptr && hands->size() >= 2 &&
                           direction.dot(hands->back() - (*hands)[hands->size() - 2]) < 0.0F;
  const Eigen::Vector2d against = hand_turned ? d : Eigen::Vector2d::Zero();
  std::vector<char> on_cut(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) on_cut[static_cast<std::size_t>(i)] = near_track(at(i), near, near, against);
  std::vector<char> skip(on_cut.size(), 0);
  for (int i = 0; i <= n;) {
    if (!on_cut[static_cast<std::size_t>(i)]) {
      ++i;
      continue;
    }
    int j = i;
    while (j + 1 <= n && on_cut[static_cast<std::size_t>(j + 1)]) ++j;
    // A run at the segment's start is skipped whatever its length when the path got here along a cut (or the
    // line starts here): it goes on along that cut.
    if ((static_cast<double>(j - i) / n) * length >= kRecutMinRunCells || (i == 0 && arrived_on_cut_)) {
      std::fill(skip.begin() + i, skip.begin() + j + 1, 1);
    }
    i = j + 1;
  }
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> parts;
  for (int i = 0; i <= n;) {
    if (skip[static_cast<std::size_t>(i)]) {
      ++i;
      continue;
    }
    int j = i;
    while (j + 1 <= n && !skip[static_cast<std::size_t>(j + 1)]) ++j;
    const Eigen::Vector2d a = i > 0 ? nearest_on_cut(at(i - 1), true) : from;
    const Eigen::Vector2d b = j < n ? nearest_on_cut(at(j + 1), true) : to;
    if ((b - a).norm() > 1e-9) parts.emplace_back(a, b);
    i = j + 1;
  }
  return parts;
}

double StrokeCutter::at_least(double cells, double metres) const {
  return std::max(cells, metres / static_cast<double>(std::min(cloth_->spacing_x(), cloth_->spacing_y())));
}

bool StrokeCutter::closes_small_loop(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const {
  if (paths_.empty() || paths_.back().size() < 3) return false;
  const auto& path = paths_.back();
  const double min_perimeter = at_least(options_.exact_min_loop_cells, options_.exact_min_loop_m);
  // Walking back along the path from its end (`from`), the loop closed by the new segment at an earlier
  // segment is that walk plus the new segment's part up to the meeting point. Segments closer than twice
  // the snap distance meet (the exact cut joins them there). Only the last min_perimeter of the path can
  // close a small loop.
  constexpr double kMeet = 2.0 * kExactSnapCells;
  double walked = 0.0;
  for (std::size_t k = path.size() - 1; k >= 2 && walked < min_perimeter; --k) {
    const Eigen::Vector2d b = path[k - 1].cast<double>();
    const Eigen::Vector2d a = path[k - 2].cast<double>();
    walked += (path[k].cast<double>() - b).norm();
    // A segment that cut nothing (it went over a cut already made) bounds no island: meeting it closes no loop.
    // A stroke going over its cut again runs back along its own path; each segment would otherwise "close" a
    // loop with the way back, and the stretch at the turn that the first pass left uncut was never cut.
    if (options_.mode == CutMode::Delete && k - 1 < path_cuts_.size() && path_cuts_[k - 1] == 0) continue;
    const auto meet = closest_points(from, to, a, b);
    if (meet.distance > kMeet) continue;
    // Meeting only where it starts: the path came back onto itself there (a way back along the cut, joined in
    // commit), which the step that got there was judged for; the new segment going on from it encloses nothing.
    // Counted, every later segment "closed a loop" there and the cut stopped (a worn blade's knot, development
    // stroke 246 moved by 1e-6 m: 0.25 m cut of the 0.65 m cutting it unmoved cuts).
    if ((meet.on_first - from).norm() <= kMeet) continue;
    const double perimeter = walked + (b - meet.on_second).norm() + (meet.on_first - from).norm();
    if (perimeter < min_perimeter) return true;
  }
  return false;
}

void StrokeCutter::start_line(GridCoord g, const Eigen::Vector2d& uv, const Eigen::Vector3f& direction,
                              TopologyChange& change) {
  line_.emplace(cloth_->columns, cloth_->rows);
  path_end_.reset();
  line_start_ = {tracks_.size(),        paths_.size(),  report_.cut_line.size(), total_.cut_line.size(),
                 report_.lines,         total_.lines,   report_.cut_length_m,    total_.cut_length_m};
  line_changed_ = false;
  commit(g, uv, direction, change);
  pending_.clear();
}

void StrokeCutter::close_line() {
  if (!line_) return;
  path_end_.reset();
  if (!follows_path()) add_line_to_report(line_->finish());
  line_.reset();
  pending_.clear();
  if (!line_changed_) forget_line();
}

void StrokeCutter::forget_line() {
  tracks_.resize(std::min(tracks_.size(), line_start_.tracks));
  track_boxes_.resize(tracks_.size());
  blade_tracks_.resize(tracks_.size());
  blade_uvs_.resize(tracks_.size());
  blade_boxes_.resize(tracks_.size());
  paths_.resize(std::min(paths_.size(), line_start_.paths));
  report_.cut_line.resize(std::min(report_.cut_line.size(), line_start_.report_cells));
  total_.cut_line.resize(std::min(total_.cut_line.size(), line_start_.total_cells));
  report_.lines = line_start_.report_lines;
  total_.lines = line_start_.total_lines;
  report_.cut_length_m = line_start_.report_length_m;
  total_.cut_length_m = line_start_.total_length_m;
  recent_.clear();
  recent_hands_.clear();
}

void StrokeCutter::add_line_to_report(const std::vector<GridCoord>& line) {
  if (line.size() < 2) return;
  const float length = cut_line_length(line, cloth_->spacing_x(), cloth_->spacing_y());
  for (StrokeReport* r : {&report_, &total_}) {
    r->cut_line.insert(r->cut_line.end(), line.begin(), line.end());
    ++r->lines;
    r->cut_length_m += length;
  }
}

TopologyChange StrokeCutter::add_sample(const StrokeSample& sample, bool touching) {
  if (!sample.position.allFinite()) return {};
  return add_sample(sample, locator_.locate(*cloth_, sample.position), touching);
}

TopologyChange StrokeCutter::add_sample(const StrokeSample& sample, const ClothPoint& at, bool touching) {
  TopologyChange change;
  if (!sample.position.allFinite()) return change;
  if (!open_) change.merge(begin_stroke());
  // Grid mode rounds (u, v) with hysteresis (grid_point); the nearest particle's own grid point flipped
  // between two rows on a stroke between them.
  const bool on_cloth = at.inside && touching;
  const Eigen::Vector3f motion =
      previous_ ? Eigen::Vector3f{sample.position - previous_->world} : Eigen::Vector3f::Zero();
  const Eigen::Vector2d uv = on_cloth ? in_slit(at.uv, sample.position, motion) : at.uv;
  const bool slid = (uv - at.uv).norm() > 1e-12;
  const Point point{uv, follows_path() ? (slid ? boundary_point(uv) : at.grid) : grid_point(uv), sample.position,
                    on_cloth, !at.inside, slid};
  if (follows_path() && line_ && previous_ && previous_->inside && point.inside) {
    // The nearest particle can be on another layer of a folded or swinging cloth: the point then jumps
    // across the cloth and back on the next sample, and a cut that followed it would cut out a sliver
    // (the straight_cut recording at 128 x 128: a 17-cell spike, 8 pieces). On the cloth the blade moves
    // about as far as the hand does; a jump far beyond that is the locator's, not the hand's.
    const Eigen::Vector2d jump = point.uv - previous_->uv;
    const double jump_m = std::hypot(jump.x() * cloth_->spacing_x(), jump.y() * cloth_->spacing_y());
    const double hand_m = static_cast<double>((sample.position - previous_->world).norm());
    const double slack_m = options_.exact_max_jump_cells * std::min(cloth_->spacing_x(), cloth_->spacing_y());
    if (jump_m > options_.exact_max_jump_ratio * hand_m + slack_m) return change;
  }
  const Eigen::Vector3f direction = previous_ ? Eigen::Vector3f{sample.position - previous_->world}
                                              : Eigen::Vector3f::Zero();
  if (direction.squaredNorm() > 0.0F) last_direction_ = direction;
  const double max_u = cloth_->columns - 1;
  const double max_v = cloth_->rows - 1;

  if (point.inside) {
    if (!line_) {
      // Entering: from the edge where the stroke crosses it (Figures 6-7), or from here on a first sample.
      std::optional<std::pair<double, double>> entry;
      if (previous_) entry = clip_to_rectangle(previous_->uv, point.uv, max_u, max_v);
      if (entry && entry->first > 0.0) {
        Eigen::Vector2d at_edge = previous_->uv + entry->first * (point.uv - previous_->uv);
        if (point.in_slit) at_edge = edge_in_slit(at_edge);
        start_line(boundary_point(at_edge), at_edge, last_direction_, change);
        anchor_ = at_edge;
        pending_.push_back(point);
      } else {
        start_line(point.grid, point.uv, last_direction_, change);
        anchor_ = point.uv;
      }
      // The hand's way in swept the cloth up to here (from beyond the edge, or from where the blade did not
      // reach it yet): a pass back over a flap that has since swung out finds material where the hand was
      // before it touched, so that stretch of the hand's path is the cut's too, and leads to where it begins.
      if (previous_) extend_blade_track(previous_->world, anchor_);
    } else {
      pending_.push_back(point);
    }
    // Simplification (Figure 8): the previous sample joins the cut when this one no longer fits a straight
    // chord from the anchor through all the samples since; a long chord joins as a whole.
    const auto fits = [&](const Eigen::Vector2d& to) {
      const Eigen::Vector2d chord = to - anchor_;
      const double length = chord.norm();
      for (std::size_t i = 0; i + 1 < pending_.size(); ++i) {
        const Eigen::Vector2d rel = pending_[i].uv - anchor_;
        if (length < 1e-9) {
          if (rel.norm() > options_.tolerance_cells) return false;
          continue;
        }
        const double along = rel.dot(chord) / length;
        const double across = std::abs(rel.x() * chord.y() - rel.y() * chord.x()) / length;
        if (across > options_.tolerance_cells || along < -backtrack_cells_) return false;
      }
      return true;
    };
    // A hand that turns back: the pass ends at the sample farthest from the anchor, where a stroke ending there
    // ends its cut (end_stroke). The fit does not see a turn: the samples on the way back lie along the chord,
    // beyond its end, so they fit and the chord only shortens; the turn was never committed and the pass stopped
    // up to max_lag_cells short of it (development stroke 826: a cut across the cloth ended 0.9 cell before the
    // edge gone there, back and there, and the piece that cutting once separates did not fall). Once the hand has
    // come back from the farthest pending sample by more than the backtrack the fit allows, and more than two
    // samples within the tolerance on either side of the path can differ by (a trembling hand goes back and forth
    // that much without turning: grid mode's 0.75-cell tolerance), that sample joins the cut and the way back goes
    // on from it.
    const auto turn = [&]() -> std::optional<std::size_t> {
      std::optional<std::size_t> apex;
      double farthest = 0.0;
      for (std::size_t i = 0; i + 1 < pending_.size(); ++i) {
        const double reach = (pending_[i].uv - anchor_).norm();
        if (reach > farthest) {
          farthest = reach;
          apex = i;
        }
      }
      if (!apex) return std::nullopt;
      const Eigen::Vector2d out = (pending_[*apex].uv - anchor_) / farthest;
      const double back = -(point.uv - pending_[*apex].uv).dot(out);
      return back > std::max(backtrack_cells_, 2.0 * options_.tolerance_cells) ? apex : std::nullopt;
    };
    if (const auto apex = pending_.size() >= 2 ? turn() : std::nullopt) {
      const Point keep = pending_[*apex];
      commit(keep.grid, keep.uv, last_direction_, change);
      anchor_ = keep.uv;
      pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(*apex) + 1);
    } else if (pending_.size() >= 2 && !fits(point.uv)) {
      const Point keep = pending_[pending_.size() - 2];
      commit(keep.grid, keep.uv, last_direction_, change);
      anchor_ = keep.uv;
      pending_.assign(1, point);
    }
    if (!pending_.empty() && (point.uv - anchor_).norm() >= options_.max_lag_cells) {
      commit(point.grid, point.uv, last_direction_, change);
      anchor_ = point.uv;
      pending_.clear();
    }
  } else if (line_) {
    // Leaving: the cut goes to where the stroke crosses the edge, not along it.
    if (!pending_.empty()) commit(pending_.back().grid, pending_.back().uv, last_direction_, change);
    if (!point.beyond) {
      // Off the cloth without crossing its edge (the blade left it): the cut ends at the last sample on it.
      extend_blade_track(point.world, path_end_ ? *path_end_ : anchor_);  // the way out, as the way in
      close_line();
      previous_ = point;
      return change;
    }
    const Eigen::Vector2d from = previous_ ? previous_->uv : anchor_;
    const auto inside_part = clip_to_rectangle(from, point.uv, max_u, max_v);
    Eigen::Vector2d at_edge = inside_part ? Eigen::Vector2d{from + inside_part->second * (point.uv - from)} : from;
    if (previous_ && previous_->in_slit) at_edge = edge_in_slit(at_edge);
    commit(boundary_point(at_edge), at_edge, last_direction_, change);
    extend_blade_track(point.world, at_edge);  // the way out to beyond the edge, as the way in above
    close_line();
  } else if (previous_ && previous_->beyond && point.beyond) {
    // Both samples beyond the edge: a fast swipe may still cross the cloth between them.
    const auto inside_part = clip_to_rectangle(previous_->uv, point.uv, max_u, max_v);
    if (inside_part && inside_part->second - inside_part->first > 1e-9) {
      const Eigen::Vector2d d = point.uv - previous_->uv;
      const Eigen::Vector2d enter = previous_->uv + inside_part->first * d;
      const Eigen::Vector2d leave = previous_->uv + inside_part->second * d;
      start_line(boundary_point(enter), enter, last_direction_, change);
      extend_blade_track(previous_->world, enter);
      commit(boundary_point(leave), leave, last_direction_, change);
      extend_blade_track(point.world, leave);
      close_line();
    }
  }
  // The samples on the cloth, for recut_parts (thinned to a twentieth of a cell). After the commits above:
  // a sample joins the track with the segment it belongs to, not with the one before.
  if (point.inside && line_) {
    const Eigen::Vector2f on = clamp_uv(point.uv).cast<float>();
    if (recent_.empty() || (recent_.back() - on).norm() >= static_cast<float>(kRecutStepCells)) {
      recent_.push_back(on);
      recent_hands_.push_back(sample.position);
    }
  }
  previous_ = point;
  return change;
}

TopologyChange StrokeCutter::end_stroke() {
  TopologyChange change;
  if (!open_) return change;
  if (line_) {
    // Figure 5: the cut reaches the stroke's end point, however short the last step (the blade stops there).
    ending_ = true;
    if (!pending_.empty()) commit(pending_.back().grid, pending_.back().uv, last_direction_, change);
    ending_ = false;
    close_line();
  }
  open_ = false;
  pending_.clear();
  previous_.reset();
  return change;
}

}  // namespace tachi::sim
