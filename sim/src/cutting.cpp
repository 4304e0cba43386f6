#include "tachi/sim/cutting.hpp"

#include "tachi/sim/cut_line.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace tachi::sim {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFU;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kEps = 1e-9;

/// Angle of a grid direction seen from +z (v grows downwards, so y = -v).
double grid_angle(double du, double dv) { return std::atan2(-dv, du); }

/// Counter-clockwise turn from angle `from` to angle `to`, in [0, 2 pi).
double ccw_turn(double from, double to) {
  double d = std::fmod(to - from, kTwoPi);
  if (d < 0.0) d += kTwoPi;
  return d;
}

/// The grid cell (top-left corner) a triangle lies in.
GridCoord cell_of(const Cloth& cloth, std::uint32_t t) {
  const auto& tri = cloth.triangles[t];
  GridCoord c = cloth.grid[tri[0]];
  for (int i = 1; i < 3; ++i) {
    c.u = std::min(c.u, cloth.grid[tri[i]].u);
    c.v = std::min(c.v, cloth.grid[tri[i]].v);
  }
  return c;
}

std::uint8_t slot_of(const std::array<std::uint32_t, 3>& tri, std::uint32_t p) {
  return static_cast<std::uint8_t>(tri[0] == p ? 0 : tri[1] == p ? 1 : 2);
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
  if (sector < kEps) sector = kTwoPi;  // the line doubles back on itself: all but the cut edge is left
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
      vertex_stamp_(static_cast<std::size_t>(cloth.columns * cloth.rows), 0) {
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
  if (!inside(g)) return out;
  for (std::uint32_t p = cloth_->index(g.u, g.v); p != kNone; p = next_copy_[p]) out.push_back(p);
  return out;
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

bool ClothCutter::mark_spring(std::uint32_t k) {
  if (spring_stamp_.size() < cloth_->spring_count()) spring_stamp_.resize(cloth_->spring_count(), 0);
  if (spring_stamp_[k] == stamp_) return false;
  spring_stamp_[k] = stamp_;
  return true;
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
    std::fill(spring_stamp_.begin(), spring_stamp_.end(), 0);
    std::fill(vertex_stamp_.begin(), vertex_stamp_.end(), 0);
    stamp_ = 1;
  }
  std::vector<LineVertex> vertices;
  const auto add_vertex = [&](std::size_t i) {
    const GridCoord g = line[i];
    auto& seen = vertex_stamp_[cloth.index(g.u, g.v)];
    if (seen == stamp_) return;
    seen = stamp_;
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
  for (const LineVertex& lv : vertices) {
    for (std::uint32_t c = cloth.index(lv.g.u, lv.g.v); c != kNone; c = next_copy_[c]) {
      for (const std::uint32_t k : cloth.springs_of(c)) {
        if (cloth.kind[k] == SpringKind::Bend) {
          if (mark_spring(k)) bends_.push_back(k);
          continue;
        }
        if (cloth.kind[k] == SpringKind::Structural) {
          const std::uint32_t x = cloth.spring_a[k] == c ? cloth.spring_b[k] : cloth.spring_a[k];
          const GridCoord far{2 * lv.g.u - cloth.grid[x].u, 2 * lv.g.v - cloth.grid[x].v};
          for (const std::uint32_t k2 : cloth.springs_of(x)) {
            if (cloth.kind[k2] != SpringKind::Bend) continue;
            const std::uint32_t y = cloth.spring_a[k2] == x ? cloth.spring_b[k2] : cloth.spring_a[k2];
            if (cloth.grid[y] == far && mark_spring(k2)) bends_.push_back(k2);
          }
        }
        if (!mark_spring(k)) continue;
        record_anchor(k);
      }
    }
  }

  // 3. Split the triangle fans (Figure 3 picks which side gets the new particle).
  for (const LineVertex& lv : vertices) {
    const auto same_grid = copies(lv.g);  // snapshot: new copies already have separated fans
    for (const std::uint32_t c : same_grid) split_fan(c, lv.to_previous, lv.to_next, change);
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

void ClothCutter::record_anchor(std::uint32_t k) {
  const Cloth& cloth = *cloth_;
  const std::uint32_t a = cloth.spring_a[k];
  const std::uint32_t b = cloth.spring_b[k];
  const GridCoord ga = cloth.grid[a];
  const GridCoord gb = cloth.grid[b];
  std::array<GridCoord, 2> cells{};
  int sides = 2;
  if (ga.v == gb.v) {
    const int u0 = std::min(ga.u, gb.u);
    cells = {GridCoord{u0, ga.v - 1}, GridCoord{u0, ga.v}};
  } else if (ga.u == gb.u) {
    const int v0 = std::min(ga.v, gb.v);
    cells = {GridCoord{ga.u - 1, v0}, GridCoord{ga.u, v0}};
  } else {
    cells[0] = {std::min(ga.u, gb.u), std::min(ga.v, gb.v)};
    sides = 1;
  }
  SpringAnchor anchor{k, {kNone, kNone}, {kNone, kNone}, {0, 0}, {0, 0}};
  for (int s = 0; s < sides; ++s) {
    for (const std::uint32_t t : cloth.triangles_of(a)) {
      if (cell_of(cloth, t) == cells[static_cast<std::size_t>(s)]) {
        anchor.triangle_a[static_cast<std::size_t>(s)] = t;
        anchor.slot_a[static_cast<std::size_t>(s)] = slot_of(cloth.triangles[t], a);
        break;
      }
    }
    for (const std::uint32_t t : cloth.triangles_of(b)) {
      if (cell_of(cloth, t) == cells[static_cast<std::size_t>(s)]) {
        anchor.triangle_b[static_cast<std::size_t>(s)] = t;
        anchor.slot_b[static_cast<std::size_t>(s)] = slot_of(cloth.triangles[t], b);
        break;
      }
    }
  }
  anchors_.push_back(anchor);
}

void ClothCutter::split_fan(std::uint32_t c, GridCoord to_previous, GridCoord to_next, TopologyChange& change) {
  Cloth& cloth = *cloth_;
  const auto incident = cloth.triangles_of(c);
  const std::size_t m = incident.size();
  if (m < 2) return;
  std::vector<std::uint32_t> tris(incident.begin(), incident.end());
  std::vector<std::size_t> parent(m);
  for (std::size_t i = 0; i < m; ++i) parent[i] = i;
  const auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
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
        parent[find(i)] = find(j);
      }
    }
  }
  std::vector<std::size_t> roots;
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
  const auto other_end = [&](std::uint32_t s, std::uint32_t p) {
    return cloth.spring_a[s] == p ? cloth.spring_b[s] : cloth.spring_a[s];
  };
  // Seed 001: a bend goes with the structural springs it spans; it survives only as a chain of two live
  // structural springs meeting at one particle (a cut through the middle particle splits that particle).
  std::uint32_t found_a = kNone;
  std::uint32_t found_b = kNone;
  if (!edge_cut(ga, gm) && !edge_cut(gm, gb)) {
    std::vector<std::uint32_t> candidates{a};
    for (const std::uint32_t p : copies(ga)) {
      if (p != a) candidates.push_back(p);
    }
    for (const std::uint32_t a_star : candidates) {
      for (const std::uint32_t s1 : cloth.springs_of(a_star)) {
        if (cloth.kind[s1] != SpringKind::Structural) continue;
        const std::uint32_t m_star = other_end(s1, a_star);
        if (!(cloth.grid[m_star] == gm)) continue;
        for (const std::uint32_t s2 : cloth.springs_of(m_star)) {
          if (cloth.kind[s2] != SpringKind::Structural) continue;
          const std::uint32_t b_star = other_end(s2, m_star);
          if (cloth.grid[b_star] == gb) {
            found_a = a_star;
            found_b = b_star;
            break;
          }
        }
        if (found_a != kNone) break;
      }
      if (found_a != kNone) break;
    }
  }
  if (found_a == kNone) {
    cloth.remove_spring(k);
    change.changed_springs.push_back(k);
    return;
  }
  if (found_a == a && found_b == b) return;
  if (found_a != a) cloth.rewire_spring(k, a, found_a);
  if (found_b != b) cloth.rewire_spring(k, b, found_b);
  change.changed_springs.push_back(k);
}

}  // namespace tachi::sim
