#include "tachi/sim/cutting.hpp"

#include "tachi/sim/cut_line.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace tachi::sim {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFU;
constexpr double kFullTurn = 4.0;  // of the diamond angle below
constexpr double kEps = 1e-9;

/// Angle of a grid direction seen from +z (v grows downwards, so y = -v), as a "diamond angle" in [0, 4):
/// monotone in the true angle and exact for the grid's small integer directions, without atan2.
double grid_angle(double du, double dv) {
  const double x = du;
  const double y = -dv;
  if (y >= 0.0) return x >= 0.0 ? y / (x + y) : 1.0 - x / (y - x);
  return x < 0.0 ? 2.0 - y / (-x - y) : 3.0 + x / (x - y);
}

/// Counter-clockwise turn from angle `from` to angle `to`, in [0, kFullTurn).
double ccw_turn(double from, double to) {
  double d = to - from;
  if (d < 0.0) d += kFullTurn;
  return d;
}

/// The grid cell (top-left corner) a triangle lies in (fixed: rewiring keeps the grid coordinates).
GridCoord cell_of(const Cloth& cloth, std::uint32_t t) {
  const auto& tri = cloth.triangles[t];
  GridCoord c = cloth.grid[tri[0]];
  for (int i = 1; i < 3; ++i) {
    c.u = std::min(c.u, cloth.grid[tri[i]].u);
    c.v = std::min(c.v, cloth.grid[tri[i]].v);
  }
  return c;
}

void sort_unique(std::vector<std::uint32_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// A particle on the line with the cut vectors of Figure 3 at its first occurrence.
struct LineVertex {
  GridCoord g;
  GridCoord to_previous;
  GridCoord to_next;
};

}  // namespace

void TopologyChange::merge(const TopologyChange& later) {
  if (later.empty()) return;
  if (empty()) {
    *this = later;
    return;
  }
  version = later.version;
  duplicated_from.insert(duplicated_from.end(), later.duplicated_from.begin(), later.duplicated_from.end());
  changed_triangles.insert(changed_triangles.end(), later.changed_triangles.begin(), later.changed_triangles.end());
  changed_springs.insert(changed_springs.end(), later.changed_springs.begin(), later.changed_springs.end());
  sort_unique(changed_triangles);
  sort_unique(changed_springs);
}

bool left_of_cut(GridCoord to_previous, GridCoord to_next, double du, double dv) {
  const double next_angle = grid_angle(to_next.u, to_next.v);
  double sector = ccw_turn(next_angle, grid_angle(to_previous.u, to_previous.v));
  if (sector < kEps) sector = kFullTurn;  // the line doubles back on itself: all but the cut edge is left
  const double d = ccw_turn(next_angle, grid_angle(du, dv));
  return d > kEps && d < sector - kEps;
}

std::vector<GridCoord> left_side_neighbours(GridCoord to_previous, GridCoord to_next) {
  static constexpr std::array<GridCoord, 8> kNeighbours{
      {{1, 0}, {1, -1}, {0, -1}, {-1, -1}, {-1, 0}, {-1, 1}, {0, 1}, {1, 1}}};
  std::vector<GridCoord> out;
  for (const GridCoord d : kNeighbours) {
    if (left_of_cut(to_previous, to_next, d.u, d.v)) out.push_back(d);
  }
  return out;
}

ClothCutter::ClothCutter(Cloth& cloth)
    : cloth_(&cloth),
      horizontal_cut_(static_cast<std::size_t>(std::max(cloth.columns - 1, 0) * cloth.rows), 0),
      vertical_cut_(static_cast<std::size_t>(cloth.columns * std::max(cloth.rows - 1, 0)), 0),
      vertex_stamp_(static_cast<std::size_t>(cloth.columns * cloth.rows), 0),
      vertex_order_(static_cast<std::size_t>(cloth.columns * cloth.rows), 0) {
  // Room for cuts to come, reserved now rather than reallocated in the middle of a stroke: half the grid
  // again in duplicates, and a spring per duplicate or two.
  const std::size_t grid_size = static_cast<std::size_t>(cloth.columns) * static_cast<std::size_t>(cloth.rows);
  cloth.reserve(cloth.particle_count() + grid_size / 2, cloth.spring_count() + grid_size);
  // Static lookups: rewiring never changes which cell a triangle lies in or where a bend is centred.
  const auto cells = static_cast<std::size_t>(std::max(cloth.columns - 1, 0) * std::max(cloth.rows - 1, 0));
  cell_triangles_.assign(cells, {kNone, kNone});
  for (std::uint32_t t = 0; t < cloth.triangle_count(); ++t) {
    const GridCoord c = cell_of(cloth, t);
    if (c.u < 0 || c.v < 0 || c.u >= cloth.columns - 1 || c.v >= cloth.rows - 1) continue;
    auto& slot = cell_triangles_[static_cast<std::size_t>(c.v * (cloth.columns - 1) + c.u)];
    (slot[0] == kNone ? slot[0] : slot[1]) = t;
  }
  bend_through_.assign(grid_size, {kNone, kNone});
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.kind[k] != SpringKind::Bend) continue;
    const GridCoord a = cloth.grid[cloth.spring_a[k]];
    const GridCoord b = cloth.grid[cloth.spring_b[k]];
    const GridCoord m{(a.u + b.u) / 2, (a.v + b.v) / 2};
    if (!inside(m)) continue;
    bend_through_[cloth.index(m.u, m.v)][a.v == b.v ? 0 : 1] = k;
  }
  sync_particles();
}

void ClothCutter::sync_particles() {
  const std::size_t n = cloth_->particle_count();
  const std::size_t grid_size = static_cast<std::size_t>(cloth_->columns) * static_cast<std::size_t>(cloth_->rows);
  next_copy_.resize(n, kNone);
  for (std::size_t i = known_particles_; i < n; ++i) {
    if (i < grid_size) continue;  // an original: heads its own list
    const GridCoord g = cloth_->grid[i];
    const std::uint32_t original = cloth_->index(g.u, g.v);
    next_copy_[i] = next_copy_[original];
    next_copy_[original] = static_cast<std::uint32_t>(i);
  }
  known_particles_ = n;
}

std::vector<std::uint32_t> ClothCutter::copies(GridCoord g) const {
  std::vector<std::uint32_t> out;
  append_copies(g, out);
  return out;
}

void ClothCutter::append_copies(GridCoord g, std::vector<std::uint32_t>& out) const {
  if (!inside(g)) return;
  for (std::uint32_t p = cloth_->index(g.u, g.v); p != kNone; p = next_copy_[p]) out.push_back(p);
}

const std::uint8_t* ClothCutter::edge_flag(GridCoord a, GridCoord b) const {
  if (!grid_adjacent(a, b) || !inside(a) || !inside(b)) return nullptr;
  const auto columns = static_cast<std::size_t>(cloth_->columns);
  if (a.v == b.v) {
    return &horizontal_cut_[static_cast<std::size_t>(a.v) * (columns - 1) + static_cast<std::size_t>(std::min(a.u, b.u))];
  }
  return &vertical_cut_[static_cast<std::size_t>(std::min(a.v, b.v)) * columns + static_cast<std::size_t>(a.u)];
}

std::uint8_t* ClothCutter::edge_flag(GridCoord a, GridCoord b) {
  return const_cast<std::uint8_t*>(std::as_const(*this).edge_flag(a, b));
}

bool ClothCutter::edge_cut(GridCoord a, GridCoord b) const {
  const std::uint8_t* flag = edge_flag(a, b);
  return flag != nullptr && *flag != 0;
}

TopologyChange ClothCutter::cut(std::span<const GridCoord> line) {
  Cloth& cloth = *cloth_;
  sync_particles();
  TopologyChange change;
  change.particle_count_before = static_cast<std::uint32_t>(cloth.particle_count());
  const std::uint32_t version_before = cloth.topology_version;
  change.version = version_before;

  // 1. Mark the new cut edges; the particles at their ends are the ones whose fans may split.
  ++stamp_;
  if (stamp_ == 0) {  // wrapped: clear the stamps once every 2^32 cuts
    std::fill(vertex_stamp_.begin(), vertex_stamp_.end(), 0);
    stamp_ = 1;
  }
  std::vector<LineVertex> vertices;
  const auto add_vertex = [&](std::size_t i) {
    const GridCoord g = line[i];
    auto& seen = vertex_stamp_[cloth.index(g.u, g.v)];
    if (seen == stamp_) return;
    seen = stamp_;
    vertex_order_[cloth.index(g.u, g.v)] = static_cast<std::uint32_t>(vertices.size());
    // Figure 3's vectors; at an end of the line the first-particle rule: the left of the single vector.
    const bool has_prev = i > 0 && grid_adjacent(line[i - 1], g);
    const bool has_next = i + 1 < line.size() && grid_adjacent(line[i + 1], g);
    GridCoord to_prev = has_prev ? GridCoord{line[i - 1].u - g.u, line[i - 1].v - g.v} : GridCoord{};
    GridCoord to_next = has_next ? GridCoord{line[i + 1].u - g.u, line[i + 1].v - g.v} : GridCoord{};
    if (!has_prev) to_prev = {-to_next.u, -to_next.v};
    if (!has_next) to_next = {-to_prev.u, -to_prev.v};
    vertices.push_back({g, to_prev, to_next});
  };
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    std::uint8_t* flag = edge_flag(line[i], line[i + 1]);
    if (flag == nullptr || *flag != 0) continue;
    *flag = 1;
    add_vertex(i);
    add_vertex(i + 1);
  }
  if (vertices.empty()) return change;

  // 2. Before anything moves, note every spring touching these particles (and the bends passing
  //    through them) with the triangles that border it.
  anchors_.clear();
  bends_.clear();
  // A spring between two particles of the line is taken once, from the one that comes first.
  const auto on_line = [&](std::uint32_t p) {
    const GridCoord g = cloth.grid[p];
    return vertex_stamp_[cloth.index(g.u, g.v)] == stamp_;
  };
  const auto order_of = [&](std::uint32_t p) {
    const GridCoord g = cloth.grid[p];
    return vertex_order_[cloth.index(g.u, g.v)];
  };
  for (std::uint32_t order = 0; order < vertices.size(); ++order) {
    const LineVertex& lv = vertices[order];
    // The two bends centred here; a bend with an end on the line is taken from that end's springs.
    for (const std::uint32_t k : bend_through_[cloth.index(lv.g.u, lv.g.v)]) {
      if (k == kNone || cloth.alive[k] == 0 || on_line(cloth.spring_a[k]) || on_line(cloth.spring_b[k])) continue;
      bends_.push_back(k);
    }
    for (std::uint32_t c = cloth.index(lv.g.u, lv.g.v); c != kNone; c = next_copy_[c]) {
      for (const std::uint32_t k : cloth.springs_of(c)) {
        const std::uint32_t x = cloth.spring_a[k] == c ? cloth.spring_b[k] : cloth.spring_a[k];
        if (on_line(x) && order_of(x) < order) continue;
        if (cloth.kind[k] == SpringKind::Bend) {
          bends_.push_back(k);
        } else {
          record_anchor(k);
        }
      }
    }
  }

  // 3. Split the triangle fans (Figure 3 picks which side gets the new particle).
  for (const LineVertex& lv : vertices) {
    // Snapshot first: the copies made here already have separated fans.
    copy_scratch_.clear();
    append_copies(lv.g, copy_scratch_);
    for (const std::uint32_t c : copy_scratch_) split_fan(c, lv.to_previous, lv.to_next, change);
  }

  // 4. Springs follow their triangles; bends that cross the cut go; completeCUT.
  resolve_springs(change);
  for (const std::uint32_t k : bends_) resolve_bend(k, change);
  for (const LineVertex& lv : vertices) {
    for (std::uint32_t c = cloth.index(lv.g.u, lv.g.v); c != kNone; c = next_copy_[c]) {
      if (!cloth.triangles_of(c).empty()) continue;
      const auto springs = cloth.springs_of(c);
      const std::vector<std::uint32_t> doomed(springs.begin(), springs.end());
      for (const std::uint32_t k : doomed) {
        cloth.remove_spring(k);
        change.changed_springs.push_back(k);
      }
    }
  }

  sort_unique(change.changed_triangles);
  sort_unique(change.changed_springs);
  if (!change.empty()) {
    // One version per cut, however many arrays it touched, so a published change list is "since v - 1".
    cloth.topology_version = version_before + 1;
  }
  change.version = cloth.topology_version;
  return change;
}

const std::array<std::uint32_t, 2>* ClothCutter::triangles_in_cell(GridCoord cell) const {
  if (cell.u < 0 || cell.v < 0 || cell.u >= cloth_->columns - 1 || cell.v >= cloth_->rows - 1) return nullptr;
  return &cell_triangles_[static_cast<std::size_t>(cell.v * (cloth_->columns - 1) + cell.u)];
}

std::array<GridCoord, 2> ClothCutter::cells_beside(GridCoord a, GridCoord b, int& sides) {
  sides = 2;
  if (a.v == b.v) {
    const int u0 = std::min(a.u, b.u);
    return {GridCoord{u0, a.v - 1}, GridCoord{u0, a.v}};
  }
  if (a.u == b.u) {
    const int v0 = std::min(a.v, b.v);
    return {GridCoord{a.u - 1, v0}, GridCoord{a.u, v0}};
  }
  sides = 1;
  return {GridCoord{std::min(a.u, b.u), std::min(a.v, b.v)}, GridCoord{}};
}

void ClothCutter::record_anchor(std::uint32_t k) {
  const Cloth& cloth = *cloth_;
  const std::uint32_t a = cloth.spring_a[k];
  const std::uint32_t b = cloth.spring_b[k];
  int sides = 0;
  const auto cells = cells_beside(cloth.grid[a], cloth.grid[b], sides);
  SpringAnchor anchor{k, {kNone, kNone}, {kNone, kNone}, {0, 0}, {0, 0}};
  // Per side, the cell's triangles that hold THESE particles (an earlier cut may have given the other
  // side its own copies and its own spring).
  for (std::size_t s = 0; s < static_cast<std::size_t>(sides); ++s) {
    const auto* in_cell = triangles_in_cell(cells[s]);
    if (in_cell == nullptr) continue;
    for (const std::uint32_t t : *in_cell) {
      if (t == kNone || cloth.triangle_alive[t] == 0) continue;
      const auto& tri = cloth.triangles[t];
      for (std::uint8_t i = 0; i < 3; ++i) {
        if (tri[i] == a && anchor.triangle_a[s] == kNone) {
          anchor.triangle_a[s] = t;
          anchor.slot_a[s] = i;
        } else if (tri[i] == b && anchor.triangle_b[s] == kNone) {
          anchor.triangle_b[s] = t;
          anchor.slot_b[s] = i;
        }
      }
    }
  }
  anchors_.push_back(anchor);
}

std::optional<std::array<std::uint32_t, 2>> ClothCutter::edge_particles(GridCoord a, GridCoord b) const {
  const Cloth& cloth = *cloth_;
  int sides = 0;
  const auto cells = cells_beside(a, b, sides);
  for (std::size_t s = 0; s < static_cast<std::size_t>(sides); ++s) {
    const auto* in_cell = triangles_in_cell(cells[s]);
    if (in_cell == nullptr) continue;
    for (const std::uint32_t t : *in_cell) {
      if (t == kNone || cloth.triangle_alive[t] == 0) continue;
      std::array<std::uint32_t, 2> found{kNone, kNone};
      for (const std::uint32_t p : cloth.triangles[t]) {
        if (cloth.grid[p] == a) found[0] = p;
        if (cloth.grid[p] == b) found[1] = p;
      }
      if (found[0] != kNone && found[1] != kNone) return found;
    }
  }
  return std::nullopt;
}

void ClothCutter::split_fan(std::uint32_t c, GridCoord to_previous, GridCoord to_next, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  const auto incident = cloth.triangles_of(c);
  const std::size_t m = incident.size();
  if (m < 2) return;
  auto& tris = fan_triangles_;
  tris.assign(incident.begin(), incident.end());
  UnionFind<std::size_t>& groups = fan_groups_;
  groups.reset(m);
  const auto find = [&groups](std::size_t i) { return groups.find(i); };
  const GridCoord g = cloth.grid[c];
  // Two triangles of the fan stay together when they share an edge c-x (the same particle x, so no
  // earlier cut separated them) whose grid edge is not cut.
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      for (const std::uint32_t x : cloth.triangles[tris[i]]) {
        if (x == c) continue;
        const auto& other = cloth.triangles[tris[j]];
        if (std::find(other.begin(), other.end(), x) == other.end()) continue;
        if (edge_cut(g, cloth.grid[x])) continue;
        groups.unite(i, j);
      }
    }
  }
  auto& roots = fan_roots_;
  roots.clear();
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t r = find(i);
    if (std::find(roots.begin(), roots.end(), r) == roots.end()) roots.push_back(r);
  }
  if (roots.size() < 2) return;
  // Figure 3: the group on the left of (v1, v2) moves to the new particle; the first group that is not
  // on the left keeps the original.
  std::size_t keeper = roots.front();
  for (const std::size_t r : roots) {
    std::size_t first = 0;
    while (find(first) != r) ++first;
    double du = 0.0;
    double dv = 0.0;
    for (const std::uint32_t x : cloth.triangles[tris[first]]) {
      if (x == c) continue;
      du += cloth.grid[x].u - g.u;
      dv += cloth.grid[x].v - g.v;
    }
    if (!left_of_cut(to_previous, to_next, du, dv)) {
      keeper = r;
      break;
    }
  }
  for (const std::size_t r : roots) {
    if (r == keeper) continue;
    const auto copy = static_cast<std::uint32_t>(cloth.duplicate_particle(c));
    change.duplicated_from.push_back(c);
    sync_particles();
    for (std::size_t i = 0; i < m; ++i) {
      if (find(i) != r) continue;
      cloth.rewire_triangle(tris[i], c, copy);
      change.changed_triangles.push_back(tris[i]);
    }
  }
}

void ClothCutter::resolve_springs(TopologyChange& change) {
  Cloth& cloth = *cloth_;
  for (const SpringAnchor& anchor : anchors_) {
    const std::uint32_t k = anchor.spring;
    if (cloth.alive[k] == 0) continue;
    std::array<std::array<std::uint32_t, 2>, 2> pair{};
    std::array<bool, 2> valid{false, false};
    for (std::size_t s = 0; s < 2; ++s) {
      const std::uint32_t ta = anchor.triangle_a[s];
      const std::uint32_t tb = anchor.triangle_b[s];
      if (ta == kNone || tb == kNone || cloth.triangle_alive[ta] == 0 || cloth.triangle_alive[tb] == 0) continue;
      pair[s] = {cloth.triangles[ta][anchor.slot_a[s]], cloth.triangles[tb][anchor.slot_b[s]]};
      valid[s] = true;
    }
    if (!valid[0] && !valid[1]) {
      // completeCUT: no triangle borders this spring any more, so it would only hold the cut shut.
      cloth.remove_spring(k);
      change.changed_springs.push_back(k);
      continue;
    }
    const std::array<std::uint32_t, 2> current{cloth.spring_a[k], cloth.spring_b[k]};
    std::size_t keep = valid[0] ? 0 : 1;
    const bool split = valid[0] && valid[1] && pair[0] != pair[1];
    if (split && pair[1] == current) keep = 1;
    if (pair[keep] != current) {
      if (current[0] != pair[keep][0]) cloth.rewire_spring(k, current[0], pair[keep][0]);
      if (current[1] != pair[keep][1]) cloth.rewire_spring(k, current[1], pair[keep][1]);
      change.changed_springs.push_back(k);
    }
    if (split) {
      // Seed 000: "the new particle is connected to the particle made in the last step with a new spring".
      const auto& other = pair[1 - keep];
      const std::uint32_t added = cloth.add_spring(other[0], other[1], cloth.kind[k]);
      cloth.rest_length[added] = cloth.rest_length[k];
      change.changed_springs.push_back(added);
    }
  }
}

void ClothCutter::resolve_bend(std::uint32_t k, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  if (cloth.alive[k] == 0) return;
  const std::uint32_t a = cloth.spring_a[k];
  const std::uint32_t b = cloth.spring_b[k];
  const GridCoord ga = cloth.grid[a];
  const GridCoord gb = cloth.grid[b];
  const GridCoord gm{(ga.u + gb.u) / 2, (ga.v + gb.v) / 2};
  // Seed 001: a bend goes with the structural springs it spans. It survives only if neither is cut and
  // the triangles along both halves meet at the same copy of the middle particle (a cut through the
  // middle splits it); its ends are then the copies those triangles hold.
  std::optional<std::array<std::uint32_t, 2>> first;
  std::optional<std::array<std::uint32_t, 2>> second;
  if (!edge_cut(ga, gm) && !edge_cut(gm, gb)) {
    first = edge_particles(ga, gm);
    second = edge_particles(gm, gb);
  }
  if (!first || !second || (*first)[1] != (*second)[0]) {
    cloth.remove_spring(k);
    change.changed_springs.push_back(k);
    return;
  }
  const std::uint32_t new_a = (*first)[0];
  const std::uint32_t new_b = (*second)[1];
  if (new_a == a && new_b == b) return;
  if (new_a != a) cloth.rewire_spring(k, a, new_a);
  if (new_b != b) cloth.rewire_spring(k, b, new_b);
  change.changed_springs.push_back(k);
}

}  // namespace tachi::sim
