#include "tachi/sim/exact_cut.hpp"

#include "tachi/sim/cut_line.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace tachi::sim {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFU;

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

double distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  const double s = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + s * d)).norm();
}

/// How close counts as touching in segments_meet, cells (see there).
constexpr double kTouchCells = 1e-5;

/// Whether the closed segments p1-p2 and q1-q2 meet (touching counts). Rest coordinates are stored as
/// floats, so "touching" allows their rounding (1e-5 cells; a float near 256 is exact to 1.5e-5): a path
/// through a particle that lies on a bend's line (the bend's crossing) touches the bend.
bool segments_meet(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                   const Eigen::Vector2d& q2) {
  constexpr double kEps = kTouchCells;
  // Boxes apart: no meeting. Most pairs tested (every bend near a cut against every cut edge of the segment)
  // are, and this saves the four point-to-segment distances below (8 % of an exact stroke's time).
  if (std::max(p1.x(), p2.x()) < std::min(q1.x(), q2.x()) - kEps || std::max(q1.x(), q2.x()) < std::min(p1.x(), p2.x()) - kEps ||
      std::max(p1.y(), p2.y()) < std::min(q1.y(), q2.y()) - kEps || std::max(q1.y(), q2.y()) < std::min(p1.y(), p2.y()) - kEps) {
    return false;
  }
  const double d1 = cross2(p2 - p1, q1 - p1);
  const double d2 = cross2(p2 - p1, q2 - p1);
  const double d3 = cross2(q2 - q1, p1 - q1);
  const double d4 = cross2(q2 - q1, p2 - q1);
  if (((d1 > kEps && d2 < -kEps) || (d1 < -kEps && d2 > kEps)) &&
      ((d3 > kEps && d4 < -kEps) || (d3 < -kEps && d4 > kEps))) {
    return true;
  }
  // Touching or collinear: an end point lies on the other segment.
  return distance_to_segment(q1, p1, p2) <= kEps || distance_to_segment(q2, p1, p2) <= kEps ||
         distance_to_segment(p1, q1, q2) <= kEps || distance_to_segment(p2, q1, q2) <= kEps;
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> clip_segment(const Eigen::Vector2d& a,
                                                                         const Eigen::Vector2d& b, double max_u,
                                                                         double max_v) {
  const auto part = clip_to_rectangle(a, b, max_u, max_v);
  if (!part) return std::nullopt;
  return std::pair{Eigen::Vector2d{a + part->first * (b - a)}, Eigen::Vector2d{a + part->second * (b - a)}};
}

/// A new spring's family from its rest direction: within 22.5 degrees of a grid axis it is structural
/// (hard, strain-limited, like the grid's), otherwise shear (soft, like the grid's diagonals).
SpringKind kind_of(const Cloth& cloth, std::uint32_t a, std::uint32_t b) {
  const double dx = std::abs(static_cast<double>(cloth.rest_uv[a].x() - cloth.rest_uv[b].x()) * cloth.spacing_x());
  const double dy = std::abs(static_cast<double>(cloth.rest_uv[a].y() - cloth.rest_uv[b].y()) * cloth.spacing_y());
  constexpr double kTan22_5 = 0.41421356237;
  return std::min(dx, dy) <= kTan22_5 * std::max(dx, dy) ? SpringKind::Structural : SpringKind::Shear;
}

}  // namespace

bool across_quad(const Cloth& cloth, std::uint32_t p, std::uint32_t x) {
  // Every pair of p's and x's triangles, counting their shared corners without branches (this ran ~1300
  // times per 64-segment stroke, 12 % of an exact stroke's instructions with std::find).
  for (const std::uint32_t tp : cloth.triangles_of(p)) {
    const auto v = cloth.triangles[tp];
    for (const std::uint32_t tx : cloth.triangles_of(x)) {
      const auto w = cloth.triangles[tx];
      const auto in_w = [&w](std::uint32_t y) {
        return static_cast<int>(y == w[0]) | static_cast<int>(y == w[1]) | static_cast<int>(y == w[2]);
      };
      if (in_w(v[0]) + in_w(v[1]) + in_w(v[2]) == 2) return true;
    }
  }
  return false;
}

namespace {

std::uint32_t other_end(const Cloth& cloth, std::uint32_t k, std::uint32_t p) {
  return cloth.spring_a[k] == p ? cloth.spring_b[k] : cloth.spring_a[k];
}

/// An undirected edge as one comparable key.
std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32U) | std::max(a, b);
}

/// The edge of triangle `tri` opposite its corner p (p must be a corner), as a key.
std::uint64_t opposite_edge(const std::array<std::uint32_t, 3>& tri, std::uint32_t p) {
  return tri[0] == p ? edge_key(tri[1], tri[2]) : tri[1] == p ? edge_key(tri[2], tri[0]) : edge_key(tri[0], tri[1]);
}

}  // namespace

ExactCutter::ExactCutter(Cloth& cloth, double snap_cells)
    : cloth_(&cloth),
      snap_(snap_cells),
      cell_columns_(std::max(cloth.columns - 1, 1)),
      cell_rows_(std::max(cloth.rows - 1, 1)) {
  // Room for the cuts to come, reserved (pages touched) now rather than reallocated mid-stroke: a cut
  // crossing a cell adds ~2 particles, ~6 springs and ~5 triangle slots there.
  const std::size_t cells = static_cast<std::size_t>(cell_columns_) * static_cast<std::size_t>(cell_rows_);
  cloth.reserve(cloth.particle_count() + cells / 2, cloth.spring_count() + 2 * cells,
                cloth.triangle_count() + 2 * cells);
  reserve_touched(triangle_stamp_, cloth.triangle_count() + 2 * cells);
  reserve_touched(edge_stamp_, cloth.triangle_count() + 2 * cells);
  reserve_touched(edge_visited_, cloth.triangle_count() + 2 * cells);
  reserve_touched(spring_stamp_, cloth.spring_count() + 2 * cells);
  cell_stamp_.assign(cells, 0);
  reserve_touched(triangle_cell_, cloth.triangle_count() + 2 * cells);
  const std::size_t particle_room = cloth.particle_count() + cells / 2;
  reserve_touched(particle_stamp_, particle_room);
  reserve_touched(split_head_, particle_room);
  reserve_touched(side_, particle_room);
  reserve_touched(snapped_, particle_room);
  reserve_touched(cut_partners_, particle_room);
  reserve_touched(on_a_cut_, particle_room);
  reserve_touched(touched_stamp_, particle_room);
  reserve_touched(wanted_marks_, particle_room);
  // The scratch sized now (stamps 0: no cut's), so that cuts only grow it by what they add.
  triangle_stamp_.resize(cloth.triangle_count(), 0);
  edge_stamp_.resize(cloth.triangle_count(), 0);
  edge_visited_.resize(cloth.triangle_count(), 0);
  spring_stamp_.resize(cloth.spring_count(), 0);
  grow_particle_scratch();
  cell_triangles_.resize(cells);
  for (std::uint32_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] != 0) register_triangle(t);
  }
}

void ExactCutter::grow_particle_scratch() {
  // Every particle gets an entry: not this cut's, no split, not snapped, not wanted.
  const std::size_t n = cloth_->particle_count();
  if (particle_stamp_.size() < n) particle_stamp_.resize(n, 0);
  if (split_head_.size() < n) split_head_.resize(n, kNone);
  if (side_.size() < n) side_.resize(n, 0.0);
  if (snapped_.size() < n) snapped_.resize(n, 0);
  if (touched_stamp_.size() < n) touched_stamp_.resize(n, 0);
  if (wanted_marks_.size() < n) wanted_marks_.resize(n, 0);
}

std::size_t ExactCutter::cell_of(std::uint32_t t) const {
  // A triangle never leaves the grid cell it was cut from, so its centroid names the cell.
  const auto& tri = cloth_->triangles[t];
  const Eigen::Vector2d c = (uv(tri[0]) + uv(tri[1]) + uv(tri[2])) / 3.0;
  const int u = std::clamp(static_cast<int>(std::floor(c.x())), 0, cell_columns_ - 1);
  const int v = std::clamp(static_cast<int>(std::floor(c.y())), 0, cell_rows_ - 1);
  return static_cast<std::size_t>(v) * static_cast<std::size_t>(cell_columns_) + static_cast<std::size_t>(u);
}

void ExactCutter::register_triangle(std::uint32_t t) {
  if (triangle_cell_.size() <= t) triangle_cell_.resize(t + 64, kNone);
  const std::size_t cell = cell_of(t);
  triangle_cell_[t] = static_cast<std::uint32_t>(cell);
  cell_triangles_[cell].push_back(t);
}

void ExactCutter::unregister_triangle(std::uint32_t t) {
  if (t >= triangle_cell_.size() || triangle_cell_[t] == kNone) return;
  auto& list = cell_triangles_[triangle_cell_[t]];
  const auto it = std::find(list.begin(), list.end(), t);
  if (it != list.end()) {
    *it = list.back();
    list.pop_back();
  }
  triangle_cell_[t] = kNone;
}

void ExactCutter::finish(TopologyChange& change, std::uint32_t version_before) {
  for (auto* list : {&change.changed_triangles, &change.changed_springs}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  // One version per cut, however many arrays it touched (as ClothCutter), so a change list is "since v - 1".
  if (!change.empty()) cloth_->topology_version = version_before + 1;
  change.version = cloth_->topology_version;
}

void ExactCutter::gather(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  // A new stamp marks this cut's triangles and particles (the stamps are cleared once every 2^32 cuts).
  if (++stamp_ == 0) {
    for (auto* stamps : {&triangle_stamp_, &particle_stamp_, &cell_stamp_, &spring_stamp_, &edge_stamp_, &touched_stamp_}) {
      std::fill(stamps->begin(), stamps->end(), 0);
    }
    stamp_ = 1;
  }
  touched_particles_.clear();
  candidates_.clear();
  if (triangle_stamp_.size() < cloth_->triangle_count()) triangle_stamp_.resize(cloth_->triangle_count(), 0);
  // Cells within reach of points every 0.1 cell along the segment: every triangle the segment meets, or
  // passes within `snap` of, lies in one of them.
  const double reach = snap_ + 0.06;
  const double length = (to - from).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / 0.1)));
  for (int i = 0; i <= steps; ++i) {
    const Eigen::Vector2d p = from + (to - from) * (static_cast<double>(i) / steps);
    const int u0 = std::clamp(static_cast<int>(std::floor(p.x() - reach)), 0, cell_columns_ - 1);
    const int u1 = std::clamp(static_cast<int>(std::floor(p.x() + reach)), 0, cell_columns_ - 1);
    const int v0 = std::clamp(static_cast<int>(std::floor(p.y() - reach)), 0, cell_rows_ - 1);
    const int v1 = std::clamp(static_cast<int>(std::floor(p.y() + reach)), 0, cell_rows_ - 1);
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        // The points are 0.1 cell apart, so each cell comes up ~10 times; once its triangles are in, they
        // all are (same candidates, same order).
        const auto cell = static_cast<std::size_t>(v * cell_columns_ + u);
        if (cell_stamp_[cell] == stamp_) continue;
        cell_stamp_[cell] = stamp_;
        for (const std::uint32_t t : cell_triangles_[cell]) {
          if (triangle_stamp_[t] == stamp_) continue;
          triangle_stamp_[t] = stamp_;
          candidates_.push_back(t);
        }
      }
    }
  }
}

std::uint32_t ExactCutter::replace_triangle(std::uint32_t t, std::array<std::uint32_t, 3> vertices,
                                            TopologyChange& change) {
  // Removes t the first time it is replaced (t stays a dead slot), then adds the piece.
  remove_triangle(t, change);
  const std::uint32_t added = cloth_->add_triangle(vertices);
  register_triangle(added);
  change.changed_triangles.push_back(added);
  if (triangle_stamp_.size() <= added) triangle_stamp_.resize(added + 64, 0);
  triangle_stamp_[added] = stamp_;
  candidates_.push_back(added);
  for (const std::uint32_t p : vertices) touch(p);
  return added;
}

void ExactCutter::insert_point(const Eigen::Vector2d& p, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  const std::size_t count = candidates_.size();
  for (std::size_t c = 0; c < count; ++c) {
    const std::uint32_t t = candidates_[c];
    if (cloth.triangle_alive[t] == 0) continue;
    const auto tri = cloth.triangles[t];
    const Eigen::Vector2d a = uv(tri[0]);
    const Eigen::Vector2d b = uv(tri[1]);
    const Eigen::Vector2d d = uv(tri[2]);
    const double area = cross2(b - a, d - a);
    if (std::abs(area) < 1e-12) continue;
    // Outside the triangle's box by more than 1e-6 cells: a barycentric coordinate below is negative by more
    // than 1e-6 / 3 (p - min corner = sum of lambda_i times corner offsets of at most a cell), far beyond its
    // 1e-12 tolerance plus rounding (~1e-13 / area, so only for areas of 1e-4 cells^2 and up): skipped anyway.
    constexpr double kBoxMargin = 1e-6;
    if (std::abs(area) >= 1e-4 &&
        (p.x() < std::min({a.x(), b.x(), d.x()}) - kBoxMargin || p.x() > std::max({a.x(), b.x(), d.x()}) + kBoxMargin ||
         p.y() < std::min({a.y(), b.y(), d.y()}) - kBoxMargin || p.y() > std::max({a.y(), b.y(), d.y()}) + kBoxMargin)) {
      continue;
    }
    const std::array<double, 3> lambda{cross2(b - p, d - p) / area, cross2(d - p, a - p) / area,
                                       cross2(a - p, b - p) / area};
    if (lambda[0] < -1e-12 || lambda[1] < -1e-12 || lambda[2] < -1e-12) continue;
    // Near a corner the path ends at that corner (it snaps); near an edge, at a new particle on the edge
    // (no sliver triangle either way).
    const std::array<Eigen::Vector2d, 3> corner{a, b, d};
    for (std::size_t i = 0; i < 3; ++i) {
      if ((p - corner[i]).norm() <= snap_) return;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      const Eigen::Vector2d e0 = corner[i];
      const Eigen::Vector2d e1 = corner[(i + 1) % 3];
      if (distance_to_segment(p, e0, e1) > snap_) continue;
      const double s = std::clamp((p - e0).dot(e1 - e0) / (e1 - e0).squaredNorm(), 0.0, 1.0);
      split_edge_at(tri[i], tri[(i + 1) % 3], s, change);
      return;
    }
    // Lumped mass: corner i gives lambda_i of its share of this triangle to the new particle.
    float new_mass = 0.0F;
    for (std::size_t i = 0; i < 3; ++i) {
      const float share = cloth.mass[tri[i]] / static_cast<float>(cloth.triangles_of(tri[i]).size());
      const float give = static_cast<float>(lambda[i]) * share;
      cloth.set_mass(tri[i], cloth.mass[tri[i]] - give);
      new_mass += give;
    }
    const std::size_t heaviest =
        static_cast<std::size_t>(std::max_element(lambda.begin(), lambda.end()) - lambda.begin());
    const auto q = static_cast<std::uint32_t>(cloth.add_particle_between(tri[0], tri[1], 0.0F, new_mass));
    cloth.position[q] = static_cast<float>(lambda[0]) * cloth.position[tri[0]] +
                        static_cast<float>(lambda[1]) * cloth.position[tri[1]] +
                        static_cast<float>(lambda[2]) * cloth.position[tri[2]];
    cloth.velocity[q] = static_cast<float>(lambda[0]) * cloth.velocity[tri[0]] +
                        static_cast<float>(lambda[1]) * cloth.velocity[tri[1]] +
                        static_cast<float>(lambda[2]) * cloth.velocity[tri[2]];
    cloth.rest_uv[q] = p.cast<float>();
    cloth.grid[q] = {static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))};
    cloth.pinned[q] = 0;
    cloth.inverse_mass[q] = 1.0F / new_mass;
    change.duplicated_from.push_back(tri[heaviest]);
    touch(q);
    replace_triangle(t, {tri[0], tri[1], q}, change);
    replace_triangle(t, {tri[1], tri[2], q}, change);
    replace_triangle(t, {tri[2], tri[0], q}, change);
    return;
  }
}

void ExactCutter::split_edge_at(std::uint32_t a, std::uint32_t b, double t, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  const std::uint32_t p = particle_on_edge(a, b, t, change);
  const auto fan = cloth.triangles_of(a);
  const std::vector<std::uint32_t> around(fan.begin(), fan.end());
  for (const std::uint32_t tri : around) {
    const auto v = cloth.triangles[tri];
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t x = v[i];
      const std::uint32_t y = v[(i + 1) % 3];
      if (!((x == a && y == b) || (x == b && y == a))) continue;
      replace_triangle(tri, {x, p, v[(i + 2) % 3]}, change);
      replace_triangle(tri, {p, y, v[(i + 2) % 3]}, change);
      break;
    }
  }
}

const ExactCutter::Split* ExactCutter::split_on(std::uint32_t a, std::uint32_t b) const {
  // Each split is listed from its lower end (split_head_, Split::next); only particles stamped by this cut
  // (every end of a crossed edge) can have one.
  const std::uint32_t lo = std::min(a, b);
  const std::uint32_t hi = std::max(a, b);
  if (lo >= particle_stamp_.size() || particle_stamp_[lo] != stamp_) return nullptr;
  for (std::uint32_t i = split_head_[lo]; i != kNone; i = splits_[i].next) {
    if (splits_[i].b == hi) return &splits_[i];
  }
  return nullptr;
}

void ExactCutter::mark_cut(std::uint32_t a, std::uint32_t b) {
  // Remembered for good: a cut edge whose lips did not open yet (a slit's last edge, whose ends are both
  // tips) opens when a later segment goes on from its tip.
  if (cut_partners_.size() < cloth_->particle_count()) {
    cut_partners_.resize(cloth_->particle_count());
    on_a_cut_.resize(cloth_->particle_count(), 0);
  }
  if (is_cut(a, b)) return;
  cut_partners_[a].push_back(b);
  cut_partners_[b].push_back(a);
  on_a_cut_[a] = 1;
  on_a_cut_[b] = 1;
}

std::uint32_t ExactCutter::particle_on_edge(std::uint32_t a, std::uint32_t b, double t, TopologyChange& change) {
  // Lumped mass (file comment): each triangle on the edge moves (1 - t) of a's share and t of b's.
  Cloth& cloth = *cloth_;
  int shared = 0;
  for (const std::uint32_t tri : cloth.triangles_of(a)) {
    const auto& v = cloth.triangles[tri];
    if (std::find(v.begin(), v.end(), b) != v.end()) ++shared;
  }
  const float fan_a = static_cast<float>(cloth.triangles_of(a).size());
  const float fan_b = static_cast<float>(cloth.triangles_of(b).size());
  const auto tf = static_cast<float>(t);
  const float give_a = static_cast<float>(shared) * (1.0F - tf) * cloth.mass[a] / fan_a;
  const float give_b = static_cast<float>(shared) * tf * cloth.mass[b] / fan_b;
  cloth.set_mass(a, cloth.mass[a] - give_a);
  cloth.set_mass(b, cloth.mass[b] - give_b);
  const auto p = static_cast<std::uint32_t>(cloth.add_particle_between(a, b, tf, give_a + give_b));
  change.duplicated_from.push_back(tf < 0.5F ? a : b);
  touch(p);
  return p;
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> ExactCutter::begin(const Eigen::Vector2d& from,
                                                                              const Eigen::Vector2d& to,
                                                                              TopologyChange& change) const {
  change.particle_count_before = static_cast<std::uint32_t>(cloth_->particle_count());
  change.version = cloth_->topology_version;
  if (!from.allFinite() || !to.allFinite()) return std::nullopt;
  const auto clipped = clip_segment(from, to, cloth_->columns - 1, cloth_->rows - 1);
  if (!clipped || !((clipped->second - clipped->first).norm() > 1e-9)) return std::nullopt;
  return clipped;
}

TopologyChange ExactCutter::cut(const Eigen::Vector2d& from_in, const Eigen::Vector2d& to_in) {
  Cloth& cloth = *cloth_;
  TopologyChange change;
  const auto segment = begin(from_in, to_in, change);
  if (!segment) return change;
  // Room for a segment of a few cells (~25 particles touched), rather than growing one push_back at a time.
  change.changed_springs.reserve(256);
  change.changed_triangles.reserve(64);
  change.duplicated_from.reserve(16);
  const std::uint32_t version_before = change.version;
  const Eigen::Vector2d from = segment->first;
  const Eigen::Vector2d to = segment->second;
  const double length = (to - from).norm();
  const Eigen::Vector2d dir = (to - from) / length;

  gather(from, to);

  // 1. End points inside a triangle become particles.
  insert_point(from, change);
  insert_point(to, change);

  // 2. Which side of the segment each particle is on, and which are on it (snapped).
  grow_particle_scratch();
  neighbourhood_.clear();
  const std::size_t original_candidates = candidates_.size();
  for (std::size_t c = 0; c < original_candidates; ++c) {
    const std::uint32_t t = candidates_[c];
    if (cloth.triangle_alive[t] == 0) continue;
    for (const std::uint32_t p : cloth.triangles[t]) {
      if (particle_stamp_[p] == stamp_) continue;
      particle_stamp_[p] = stamp_;
      split_head_[p] = kNone;
      neighbourhood_.push_back(p);
      side_[p] = cross2(dir, uv(p) - from);
      // Farther than snap from the segment's line (by more than any rounding of side_): farther from the
      // segment too, without its distance (most of the neighbourhood is).
      snapped_[p] = std::abs(side_[p]) > snap_ + 1e-9 ? 0 : distance_to_segment(uv(p), from, to) <= snap_ ? 1 : 0;
    }
  }
  // Edges whose ends are strictly on opposite sides, crossed within the segment.
  splits_.clear();
  for (std::size_t c = 0; c < original_candidates; ++c) {
    const std::uint32_t t = candidates_[c];
    if (cloth.triangle_alive[t] == 0) continue;
    const auto tri = cloth.triangles[t];
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t lo = std::min(tri[i], tri[(i + 1) % 3]);
      const std::uint32_t hi = std::max(tri[i], tri[(i + 1) % 3]);
      if (snapped_[lo] != 0 || snapped_[hi] != 0) continue;
      if (!((side_[lo] > 0.0 && side_[hi] < 0.0) || (side_[lo] < 0.0 && side_[hi] > 0.0))) continue;
      if (split_on(lo, hi) != nullptr) continue;
      const double t_lo = side_[lo] / (side_[lo] - side_[hi]);
      const Eigen::Vector2d x = uv(lo) + t_lo * (uv(hi) - uv(lo));
      const double s = (x - from).dot(dir);
      if (s < -1e-9 || s > length + 1e-9) continue;
      splits_.push_back({lo, hi, t_lo, kNone, split_head_[lo]});
      split_head_[lo] = static_cast<std::uint32_t>(splits_.size() - 1);
    }
  }
  for (Split& split : splits_) split.particle = particle_on_edge(split.a, split.b, split.t, change);

  // 3. Split the crossed triangles so that the path's piece in each is an edge.
  cut_pairs_.clear();
  for (std::size_t c = 0; c < original_candidates; ++c) {
    const std::uint32_t t = candidates_[c];
    if (cloth.triangle_alive[t] == 0) continue;
    const auto v = cloth.triangles[t];
    std::array<std::uint32_t, 3> on_edge{kNone, kNone, kNone};  // edge i runs from v[i] to v[i + 1]
    int splits = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      if (const Split* s = split_on(v[i], v[(i + 1) % 3])) {
        on_edge[i] = s->particle;
        ++splits;
      }
    }
    const auto snapped = [&](std::uint32_t p) { return particle_stamp_[p] == stamp_ && snapped_[p] != 0; };
    if (splits == 0) {
      // The path runs along an existing edge when two corners are on it.
      for (std::size_t i = 0; i < 3; ++i) {
        if (snapped(v[i]) && snapped(v[(i + 1) % 3])) {
          cut_pairs_.push_back({std::min(v[i], v[(i + 1) % 3]), std::max(v[i], v[(i + 1) % 3])});
        }
      }
    } else if (splits == 1) {
      const std::size_t i = on_edge[0] != kNone ? 0 : on_edge[1] != kNone ? 1 : 2;
      const std::uint32_t a = v[i];
      const std::uint32_t b = v[(i + 1) % 3];
      const std::uint32_t opposite = v[(i + 2) % 3];
      const std::uint32_t p = on_edge[i];
      replace_triangle(t, {a, p, opposite}, change);
      replace_triangle(t, {p, b, opposite}, change);
      if (snapped(opposite)) cut_pairs_.push_back({std::min(p, opposite), std::max(p, opposite)});
    } else if (splits == 2) {
      // Edge k has no split: its ends a, b; c is the corner the path cuts off.
      const std::size_t k = on_edge[0] == kNone ? 0 : on_edge[1] == kNone ? 1 : 2;
      const std::uint32_t a = v[k];
      const std::uint32_t b = v[(k + 1) % 3];
      const std::uint32_t corner = v[(k + 2) % 3];
      const std::uint32_t q = on_edge[(k + 1) % 3];  // on b-c
      const std::uint32_t p = on_edge[(k + 2) % 3];  // on c-a
      replace_triangle(t, {q, corner, p}, change);
      // The quad a, b, q, p by its shorter diagonal.
      if ((uv(a) - uv(q)).squaredNorm() <= (uv(b) - uv(p)).squaredNorm()) {
        replace_triangle(t, {a, b, q}, change);
        replace_triangle(t, {a, q, p}, change);
      } else {
        replace_triangle(t, {a, b, p}, change);
        replace_triangle(t, {b, q, p}, change);
      }
      cut_pairs_.push_back({std::min(p, q), std::max(p, q)});
    }
  }
  std::sort(cut_pairs_.begin(), cut_pairs_.end());
  cut_pairs_.erase(std::unique(cut_pairs_.begin(), cut_pairs_.end()), cut_pairs_.end());
  for (const auto& [p, q] : cut_pairs_) {
    mark_cut(p, q);
    max_deviation_ = std::max({max_deviation_, distance_to_segment(uv(p), from, to), distance_to_segment(uv(q), from, to)});
    cut_edges_.push_back({cloth.rest_uv[p], cloth.rest_uv[q]});
    cut_length_m_ += cloth.rest_distance(p, q);
  }

  // 4. Separate the sides along the cut edges.
  on_cut_.clear();
  for (const auto& [p, q] : cut_pairs_) {
    on_cut_.push_back(p);
    on_cut_.push_back(q);
  }
  std::sort(on_cut_.begin(), on_cut_.end());
  on_cut_.erase(std::unique(on_cut_.begin(), on_cut_.end()), on_cut_.end());
  for (const std::uint32_t c : on_cut_) separate(c, change);

  // Springs follow the triangles around everything touched; bends across or onto the cut go.
  for (const std::uint32_t c : on_cut_) touch(c);
  std::sort(touched_particles_.begin(), touched_particles_.end());
  spring_stamp_.resize(cloth.spring_count(), 0);  // springs added while re-deriving are triangle edges
  for (const std::uint32_t p : touched_particles_) rederive_springs(p, change);
  if (!cut_pairs_.empty()) {
    // The box of all cut edges: a bend apart from it (segments_meet's own first test, against the union of
    // the edges' boxes) meets none of them.
    Eigen::Vector2d box_lo = uv(cut_pairs_.front()[0]);
    Eigen::Vector2d box_hi = box_lo;
    for (const auto& pair : cut_pairs_) {
      for (const std::uint32_t x : pair) {
        box_lo = box_lo.cwiseMin(uv(x));
        box_hi = box_hi.cwiseMax(uv(x));
      }
    }
    cut_edges_uv_.clear();
    for (const auto& [x, y] : cut_pairs_) {
      cut_edges_uv_.push_back({uv(x), uv(y), uv(x).cwiseMin(uv(y)), uv(x).cwiseMax(uv(y))});
    }
    if (spring_stamp_.size() < cloth.spring_count()) spring_stamp_.resize(cloth.spring_count(), 0);
    // The touched particles not in it yet (those stamped in step 2 are: reading their lists again would
    // only meet bends tested already).
    for (const std::uint32_t p : touched_particles_) {
      if (p >= particle_stamp_.size() || particle_stamp_[p] != stamp_) neighbourhood_.push_back(p);
    }
    for (const std::uint32_t p : neighbourhood_) {
      // The list is read first and the bends that meet the cut removed after it, in the same order (no test
      // depends on another bend's removal): no copy of every list.
      doomed_.clear();
      for (const std::uint32_t k : cloth.springs_of(p)) {
        if (cloth.kind[k] != SpringKind::Bend || cloth.alive[k] == 0) continue;
        // Met from its other end already: it stayed, and would again (the test is geometry only).
        if (spring_stamp_[k] == stamp_) continue;
        spring_stamp_[k] = stamp_;
        const Eigen::Vector2d a = uv(cloth.spring_a[k]);
        const Eigen::Vector2d b = uv(cloth.spring_b[k]);
        if (std::max(a.x(), b.x()) < box_lo.x() - kTouchCells || box_hi.x() < std::min(a.x(), b.x()) - kTouchCells ||
            std::max(a.y(), b.y()) < box_lo.y() - kTouchCells || box_hi.y() < std::min(a.y(), b.y()) - kTouchCells) {
          continue;
        }
        const Eigen::Vector2d bend_lo = a.cwiseMin(b);
        const Eigen::Vector2d bend_hi = a.cwiseMax(b);
        for (const CutEdge& edge : cut_edges_uv_) {
          // segments_meet's first test, on boxes computed once: most cut edges are apart from the bend.
          if (bend_hi.x() < edge.lo.x() - kTouchCells || edge.hi.x() < bend_lo.x() - kTouchCells ||
              bend_hi.y() < edge.lo.y() - kTouchCells || edge.hi.y() < bend_lo.y() - kTouchCells) {
            continue;
          }
          if (!segments_meet(a, b, edge.x, edge.y)) continue;
          doomed_.push_back(k);
          break;
        }
      }
      for (const std::uint32_t k : doomed_) {
        cloth.remove_spring(k);
        change.changed_springs.push_back(k);
      }
    }
  }

  // Bends for the new triangles, after the removal above (they never cross the path: see add_bends).
  if (!cut_pairs_.empty()) {
    edge_stamp_.resize(cloth.triangle_count(), 0);
    edge_visited_.resize(cloth.triangle_count(), 0);
    for (const std::uint32_t p : touched_particles_) add_bends(p, change);
  }

  finish(change, version_before);
  return change;
}

void ExactCutter::add_bends(std::uint32_t p, TopologyChange& change) {
  // No bend shorter than a cell: between the close corners of the small triangles along a cut a bend acts
  // as one more in-plane spring (XPBD compliance does not scale with length), stiffening the cut's tip so
  // that its structural springs take the load (a flap cut rested at 22 % instead of 10 %).
  constexpr double kMinBendCells = 1.0;
  // The grid's bends span two cells along a row or column; around a cut the triangles are no longer a grid,
  // so a bend goes across each edge two triangles share, between their far corners: Provot's flexion spring
  // (Provot 1995; seed 001 section 2.1, Figure 3: it resists folding between the two particles) in the form it takes
  // on a triangle mesh, one across each interior edge.
  // Only where those corners lie on opposite sides of the shared edge and the edge's ends on opposite sides
  // of the bend: the bend then stays inside the two triangles, so it crosses no cut.
  // Each (triangle, edge) is visited once per cut: from the edge's other end it would find the same
  // triangles, the same geometry and the bend it made (adding bends changes neither triangles nor cut edges),
  // so that second visit is skipped (add_bends was 30 % of an exact stroke's instructions before).
  Cloth& cloth = *cloth_;
  constexpr std::array<std::size_t, 3> kNext{1, 2, 0};
  const auto visit = [&](std::uint32_t t, std::size_t e) {
    if (edge_stamp_[t] != stamp_) {
      edge_stamp_[t] = stamp_;
      edge_visited_[t] = 0;
    }
    const auto bit = static_cast<std::uint8_t>(1U << e);
    const bool seen = (edge_visited_[t] & bit) != 0;
    edge_visited_[t] = static_cast<std::uint8_t>(edge_visited_[t] | bit);
    return !seen;
  };
  for (const std::uint32_t t : cloth.triangles_of(p)) {  // add_spring leaves the triangle lists alone
    const auto tri = cloth.triangles[t];
    const std::size_t at = tri[0] == p ? 0 : tri[1] == p ? 1 : 2;
    // The two edges at p, in the order of the triangle's edges: e runs from tri[e] to tri[e + 1].
    const std::size_t before = kNext[kNext[at]];
    const std::array<std::size_t, 2> edges_at_p{std::min(before, at), std::max(before, at)};
    for (const std::size_t e : edges_at_p) {
      const std::uint32_t a = tri[e];
      const std::uint32_t b = tri[kNext[e]];
      const std::uint32_t far = tri[kNext[kNext[e]]];
      // Not a cut edge whose lips have not opened yet (a slit's last edge: both triangles still share it).
      if (!visit(t, e) || is_cut(a, b)) continue;
      std::uint32_t only_other = kNone;  // the one other triangle on a-b, if there is exactly one
      std::size_t others = 0;
      std::size_t only_other_edge = 0;
      bool bend_there = false;
      for (const std::uint32_t t2 : cloth.triangles_of(a)) {
        const auto& other = cloth.triangles[t2];
        if (t2 == t || (other[0] != b && other[1] != b && other[2] != b)) continue;
        ++others;
        const std::size_t far2_at = other[0] != a && other[0] != b ? 0 : other[1] != a && other[1] != b ? 1 : 2;
        const std::uint32_t far2 = other[far2_at];
        only_other = t2;
        only_other_edge = kNext[far2_at];
        const double s1 = cross2(uv(b) - uv(a), uv(far) - uv(a));
        const double s2 = cross2(uv(b) - uv(a), uv(far2) - uv(a));
        const double s3 = cross2(uv(far2) - uv(far), uv(a) - uv(far));
        const double s4 = cross2(uv(far2) - uv(far), uv(b) - uv(far));
        const double bend_cells = (uv(far2) - uv(far)).norm();
        // An end of the shared edge on the bend's line is on neither side: the two triangles are flat along a
        // straight line through it and the bend would run along their outer edges (springs already), not inside
        // them. Where that line is a grid row s3 or s4 is exactly 0 and no bend was ever added; along a straight
        // cut the new particles of a segment lie on one line only up to the rounding of their float rest
        // coordinates, so between two of them across the edge at a third the sign was rounding noise, and a
        // stroke moved by 1e-6 m put a bend along the cut on the other lip (docs/cutting.md, "The bend along a
        // straight cut"). So "on the line" is within kTouchCells, the removal's "touching" above.
        const double on_line = kTouchCells * bend_cells;
        if (!(s1 * s2 < 0.0 && s3 * s4 < 0.0) || std::min(std::abs(s3), std::abs(s4)) <= on_line ||
            bend_cells < kMinBendCells) {
          continue;
        }
        bend_there = true;
        // A spring far-far2 is in both ends' lists: the shorter one is searched.
        const bool from_far = cloth.springs_of(far).size() <= cloth.springs_of(far2).size();
        const std::uint32_t near_end = from_far ? far : far2;
        const std::uint32_t far_end = from_far ? far2 : far;
        const auto springs = cloth.springs_of(near_end);
        const bool exists = std::any_of(springs.begin(), springs.end(),
                                        [&](std::uint32_t k) { return other_end(cloth, k, near_end) == far_end; });
        if (!exists) change.changed_springs.push_back(cloth.add_spring(far, far2, SpringKind::Bend));
      }
      // From the other triangle the same edge would find only t, and the bend between their far corners
      // that is there now: nothing to do. (When the test above failed it is repeated from there: the
      // mirrored cross products may round the other way.)
      if (others == 1 && bend_there) visit(only_other, only_other_edge);
    }
  }
}

void ExactCutter::remove_triangle(std::uint32_t t, TopologyChange& change) {
  if (cloth_->triangle_alive[t] == 0) return;
  unregister_triangle(t);
  cloth_->remove_triangle(t);
  change.changed_triangles.push_back(t);
  for (const std::uint32_t p : cloth_->triangles[t]) touch(p);
}

TopologyChange ExactCutter::remove_crossed(const Eigen::Vector2d& from_in, const Eigen::Vector2d& to_in) {
  Cloth& cloth = *cloth_;
  TopologyChange change;
  const auto segment = begin(from_in, to_in, change);
  if (!segment) return change;
  const std::uint32_t version_before = change.version;
  const Eigen::Vector2d from = segment->first;
  const Eigen::Vector2d to = segment->second;
  gather(from, to);
  // The mesh edges the blade crosses, and their springs.
  cut_pairs_.clear();
  for (const std::uint32_t t : candidates_) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t a = tri[i];
      const std::uint32_t b = tri[(i + 1) % 3];
      if (segments_meet(uv(a), uv(b), from, to)) cut_pairs_.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(cut_pairs_.begin(), cut_pairs_.end());
  cut_pairs_.erase(std::unique(cut_pairs_.begin(), cut_pairs_.end()), cut_pairs_.end());
  for (const auto& [a, b] : cut_pairs_) {
    mark_cut(a, b);
    const auto springs = cloth.springs_of(a);
    bends_.assign(springs.begin(), springs.end());
    for (const std::uint32_t k : bends_) {
      if (cloth.kind[k] != SpringKind::Bend && other_end(cloth, k, a) == b) {
        cloth.remove_spring(k);
        change.changed_springs.push_back(k);
      }
    }
  }
  // Triangles with two deleted edges go; the particle between those edges is completeCUT.
  std::vector<std::uint32_t> complete_cut;
  for (const std::uint32_t t : candidates_) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto tri = cloth.triangles[t];
    std::array<bool, 3> deleted{};
    for (std::size_t i = 0; i < 3; ++i) deleted[i] = is_cut(tri[i], tri[(i + 1) % 3]);
    for (std::size_t i = 0; i < 3; ++i) {
      // Edges i - 1 and i meet at vertex i.
      if (deleted[(i + 2) % 3] && deleted[i]) complete_cut.push_back(tri[i]);
    }
    if (static_cast<int>(deleted[0]) + static_cast<int>(deleted[1]) + static_cast<int>(deleted[2]) >= 2) {
      remove_triangle(t, change);
    }
  }
  for (const std::uint32_t c : complete_cut) {
    const auto tris = cloth.triangles_of(c);
    const std::vector<std::uint32_t> doomed(tris.begin(), tris.end());
    for (const std::uint32_t t : doomed) remove_triangle(t, change);
    touch(c);
  }
  // completeCUT's clean-up: springs follow the surviving triangles.
  std::sort(touched_particles_.begin(), touched_particles_.end());
  for (const std::uint32_t p : touched_particles_) {
    const auto springs = cloth.springs_of(p);
    bends_.assign(springs.begin(), springs.end());
    const bool isolated = cloth.triangles_of(p).empty();
    for (const std::uint32_t k : bends_) {
      const std::uint32_t x = other_end(cloth, k, p);
      bool bordered = false;
      if (!isolated && cloth.kind[k] != SpringKind::Bend) {
        for (const std::uint32_t t : cloth.triangles_of(p)) {
          const auto& tri = cloth.triangles[t];
          bordered = bordered || std::find(tri.begin(), tri.end(), x) != tri.end();
        }
      }
      const bool bend_kept = !isolated && cloth.kind[k] == SpringKind::Bend && !segments_meet(uv(p), uv(x), from, to) &&
                             !cloth.triangles_of(x).empty();
      if (bordered || bend_kept) continue;
      cloth.remove_spring(k);
      change.changed_springs.push_back(k);
    }
  }
  // Bends across the blade's path (seed 001: "if the structural spring in a direction is cut, so too is its bend").
  for (const std::uint32_t t : candidates_) {
    for (const std::uint32_t p : cloth.triangles[t]) {
      const auto springs = cloth.springs_of(p);
      bends_.assign(springs.begin(), springs.end());
      for (const std::uint32_t k : bends_) {
        if (cloth.kind[k] != SpringKind::Bend) continue;
        if (!segments_meet(uv(cloth.spring_a[k]), uv(cloth.spring_b[k]), from, to)) continue;
        cloth.remove_spring(k);
        change.changed_springs.push_back(k);
      }
    }
  }
  finish(change, version_before);
  return change;
}

void ExactCutter::separate(std::uint32_t c, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  const auto incident = cloth.triangles_of(c);
  fan_.assign(incident.begin(), incident.end());  // rewired below: a copy (member scratch, no allocation)
  const auto& tris = fan_;
  const std::size_t m = tris.size();
  if (m < 2) return;
  UnionFind<std::size_t>& groups = fan_groups_;
  groups.reset(m);
  const auto find = [&groups](std::size_t i) { return groups.find(i); };
  // Two triangles of the fan stay together across a shared edge c-x (the same particle x) not cut now.
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      for (const std::uint32_t x : cloth.triangles[tris[i]]) {
        if (x == c) continue;
        const auto& other = cloth.triangles[tris[j]];
        if (std::find(other.begin(), other.end(), x) == other.end() || is_cut(c, x)) continue;
        groups.unite(i, j);
      }
    }
  }
  auto& roots = fan_roots_;
  roots.clear();
  for (std::size_t i = 0; i < m; ++i) {
    if (std::find(roots.begin(), roots.end(), find(i)) == roots.end()) roots.push_back(find(i));
  }
  // The first group keeps the particle; every other one gets a copy.
  for (std::size_t r = 1; r < roots.size(); ++r) {
    const auto copy = static_cast<std::uint32_t>(cloth.duplicate_particle(c));
    change.duplicated_from.push_back(c);
    touch(copy);
    const auto partners = cut_partners_[c].items();
    partners_.assign(partners.begin(), partners.end());  // the copy has the same cut edges (mark_cut may move the lists)
    for (const std::uint32_t y : partners_) mark_cut(copy, y);
    for (std::size_t i = 0; i < m; ++i) {
      if (find(i) != roots[r]) continue;
      cloth.rewire_triangle(tris[i], c, copy);
      change.changed_triangles.push_back(tris[i]);
      for (const std::uint32_t p : cloth.triangles[tris[i]]) touch(p);
    }
  }
}

void ExactCutter::rederive_springs(std::uint32_t p, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  // The structural and shear springs of p are exactly its triangles' edges (completeCUT, seed 001: a
  // particle without triangles keeps no spring, a spring no triangle borders is removed).
  // wanted_: p's triangles' other corners, in order; wanted_marks_ says which of them is wanted (mark) and
  // which has its spring already (mark + 1), instead of searching and erasing in wanted_.
  wanted_mark_ += 2;
  if (wanted_mark_ < 2) {  // wrapped: old marks could read as this call's
    std::fill(wanted_marks_.begin(), wanted_marks_.end(), 0);
    wanted_mark_ = 2;
  }
  const std::uint32_t wanted = wanted_mark_;
  const std::uint32_t found = wanted_mark_ + 1;
  if (wanted_marks_.size() < cloth.particle_count()) wanted_marks_.resize(cloth.particle_count(), 0);
  wanted_.clear();
  opposite_edges_.clear();
  for (const std::uint32_t t : cloth.triangles_of(p)) {
    for (const std::uint32_t x : cloth.triangles[t]) {
      if (x != p && wanted_marks_[x] != wanted) {
        wanted_marks_[x] = wanted;
        wanted_.push_back(x);
      }
    }
  }
  // Removals wait until the list has been read (no decision below depends on another spring's removal),
  // then happen in the same order: no copy of the list.
  doomed_.clear();
  for (const std::uint32_t k : cloth.springs_of(p)) {
    if (cloth.kind[k] == SpringKind::Bend) {
      if (cloth.triangles_of(p).empty()) doomed_.push_back(k);
      continue;
    }
    const std::uint32_t x = other_end(cloth, k, p);
    if (wanted_marks_[x] == wanted) {
      wanted_marks_[x] = found;  // already there
      continue;
    }
    if (cloth.kind[k] == SpringKind::Shear) {
      // Kept from its other end already this cut (triangles do not change while springs are re-derived,
      // and across_quad is symmetric): the same answer without the search.
      if (k < spring_stamp_.size() && spring_stamp_[k] == stamp_) continue;
      // across_quad(p, x), by keys when p and x share no triangle (always, unless two springs join them):
      // two of their triangles then share two corners exactly when one of x's has, opposite x, the edge
      // one of p's has opposite p.
      const bool share_a_triangle = wanted_marks_[x] == found;
      if (opposite_edges_.empty()) {
        for (const std::uint32_t t : cloth.triangles_of(p)) opposite_edges_.push_back(opposite_edge(cloth.triangles[t], p));
      }
      const auto x_fan = cloth.triangles_of(x);
      const bool across =
          share_a_triangle ? across_quad(cloth, p, x) : std::any_of(x_fan.begin(), x_fan.end(), [&](std::uint32_t t) {
            const std::uint64_t key = opposite_edge(cloth.triangles[t], x);
            return std::find(opposite_edges_.begin(), opposite_edges_.end(), key) != opposite_edges_.end();
          });
      if (across) {
        if (k < spring_stamp_.size()) spring_stamp_[k] = stamp_;
        continue;
      }
    }
    doomed_.push_back(k);
  }
  for (const std::uint32_t k : doomed_) {
    cloth.remove_spring(k);
    change.changed_springs.push_back(k);
  }
  for (const std::uint32_t x : wanted_) {
    if (wanted_marks_[x] == wanted) change.changed_springs.push_back(cloth.add_spring(p, x, kind_of(cloth, p, x)));
  }
}

}  // namespace tachi::sim
