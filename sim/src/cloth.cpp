#include "tachi/sim/cloth.hpp"

#include <algorithm>
#include <cmath>

namespace tachi::sim {

std::optional<const char*> validate(const ClothConfig& config) {
  if (config.columns < 2 || config.rows < 2) return "grid must be at least 2 x 2 particles";
  if (static_cast<long long>(config.columns) * config.rows > (1LL << 26)) return "grid has too many particles";
  if (!(config.width_m > 0.0F) || !(config.height_m > 0.0F) || !std::isfinite(config.width_m) ||
      !std::isfinite(config.height_m)) {
    return "cloth size must be a positive finite length";
  }
  if (!(config.total_mass_kg > 0.0F) || !std::isfinite(config.total_mass_kg)) return "cloth mass must be positive";
  return std::nullopt;
}

std::vector<std::uint32_t> pinned_particles(int columns, int rows, PinMode pin) {
  std::vector<std::uint32_t> out;
  (void)rows;
  switch (pin) {
    case PinMode::Corners:
      out = {0U, static_cast<std::uint32_t>(columns - 1)};
      break;
    case PinMode::TopEdge:
      for (int u = 0; u < columns; ++u) out.push_back(static_cast<std::uint32_t>(u));
      break;
    case PinMode::None:
      break;
  }
  return out;
}

Cloth::Cloth(const ClothConfig& config)
    : columns(config.columns),
      rows(config.rows),
      spacing_x_(config.width_m / static_cast<float>(config.columns - 1)),
      spacing_y_(config.height_m / static_cast<float>(config.rows - 1)) {
  const std::size_t n = static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows);
  const float particle_mass = config.total_mass_kg / static_cast<float>(n);
  position.reserve(n);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < columns; ++u) {
      position.emplace_back(static_cast<float>(u) * spacing_x_ - 0.5F * config.width_m,
                            0.5F * config.height_m - static_cast<float>(v) * spacing_y_, 0.0F);
      grid.push_back({u, v});
      rest_uv.emplace_back(static_cast<float>(u), static_cast<float>(v));
    }
  }
  velocity.assign(n, Eigen::Vector3f::Zero());
  mass.assign(n, particle_mass);
  inverse_mass.assign(n, 1.0F / particle_mass);
  pinned.assign(n, 0);
  spring_incidence_.resize(n);
  triangle_incidence_.resize(n);
  for (const std::uint32_t p : pinned_particles(columns, rows, config.pin)) set_pinned(p, true);

  // Kinds in blocks, each in row-major order, so a solver sweep over one kind walks memory forwards.
  const auto cols = static_cast<std::size_t>(columns);
  const auto rws = static_cast<std::size_t>(rows);
  const std::size_t structural = (cols - 1) * rws + cols * (rws - 1);
  const std::size_t shear = 2 * (cols - 1) * (rws - 1);
  const std::size_t bend = (cols > 2 ? (cols - 2) * rws : 0) + (rws > 2 ? cols * (rws - 2) : 0);
  const std::size_t total = structural + shear + bend;
  spring_a.reserve(total);
  spring_b.reserve(total);
  rest_length.reserve(total);
  kind.reserve(total);
  alive.reserve(total);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < columns; ++u) {
      if (u + 1 < columns) add_spring(index(u, v), index(u + 1, v), SpringKind::Structural);
      if (v + 1 < rows) add_spring(index(u, v), index(u, v + 1), SpringKind::Structural);
    }
  }
  for (int v = 0; v + 1 < rows; ++v) {
    for (int u = 0; u + 1 < columns; ++u) {
      // The first diagonal (u,v)-(u+1,v+1) is the one the cell's two triangles share.
      add_spring(index(u, v), index(u + 1, v + 1), SpringKind::Shear);
      add_spring(index(u + 1, v), index(u, v + 1), SpringKind::Shear);
    }
  }
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < columns; ++u) {
      if (u + 2 < columns) add_spring(index(u, v), index(u + 2, v), SpringKind::Bend);
      if (v + 2 < rows) add_spring(index(u, v), index(u, v + 2), SpringKind::Bend);
    }
  }
  triangles.reserve(2 * (cols - 1) * (rws - 1));
  triangle_alive.reserve(2 * (cols - 1) * (rws - 1));
  for (int v = 0; v + 1 < rows; ++v) {
    for (int u = 0; u + 1 < columns; ++u) {
      const std::uint32_t p00 = index(u, v), p10 = index(u + 1, v), p01 = index(u, v + 1), p11 = index(u + 1, v + 1);
      add_triangle({p00, p01, p11});
      add_triangle({p00, p11, p10});
    }
  }
  topology_version = 0;
  spring_edits.clear();  // construction is not an edit: a solver starts with a full build
}

std::size_t Cloth::alive_spring_count() const {
  return static_cast<std::size_t>(std::count(alive.begin(), alive.end(), std::uint8_t{1}));
}

std::size_t Cloth::alive_triangle_count() const {
  return static_cast<std::size_t>(std::count(triangle_alive.begin(), triangle_alive.end(), std::uint8_t{1}));
}

void Cloth::reserve(std::size_t particles, std::size_t springs, std::size_t triangle_slots) {
  reserve_touched(triangles, triangle_slots);
  reserve_touched(triangle_alive, triangle_slots);
  reserve_touched(spring_edits, springs);
  reserve_touched(position, particles);
  reserve_touched(velocity, particles);
  reserve_touched(mass, particles);
  reserve_touched(inverse_mass, particles);
  reserve_touched(grid, particles);
  reserve_touched(rest_uv, particles);
  reserve_touched(pinned, particles);
  reserve_touched(spring_incidence_, particles);
  reserve_touched(triangle_incidence_, particles);
  reserve_touched(spring_a, springs);
  reserve_touched(spring_b, springs);
  reserve_touched(rest_length, springs);
  reserve_touched(kind, springs);
  reserve_touched(alive, springs);
}

std::size_t Cloth::duplicate_particle(std::size_t i) {
  const std::size_t copy = position.size();
  // Copy by value first: push_back may reallocate and invalidate references into the same vector.
  const Eigen::Vector3f p = position[i];
  const Eigen::Vector3f vel = velocity[i];
  const GridCoord g = grid[i];
  const Eigen::Vector2f uv = rest_uv[i];
  const std::uint8_t is_pinned = pinned[i];
  const float half = 0.5F * mass[i];
  position.push_back(p);
  velocity.push_back(vel);
  grid.push_back(g);
  rest_uv.push_back(uv);
  pinned.push_back(is_pinned);
  mass[i] = half;
  mass.push_back(half);
  // Particle i may be held by the hand (inverse mass 0 without being pinned): it stays held, the copy
  // is free unless pinned.
  inverse_mass[i] = (is_pinned != 0 || inverse_mass[i] == 0.0F) ? 0.0F : 1.0F / half;
  inverse_mass.push_back(is_pinned != 0 ? 0.0F : 1.0F / half);
  spring_incidence_.emplace_back();
  triangle_incidence_.emplace_back();
  ++topology_version;
  return copy;
}

std::size_t Cloth::add_particle_between(std::size_t a, std::size_t b, float t, float new_mass) {
  const std::size_t p = position.size();
  // By value first: push_back may reallocate the vectors these come from.
  const Eigen::Vector3f x = (1.0F - t) * position[a] + t * position[b];
  const Eigen::Vector3f vel = (1.0F - t) * velocity[a] + t * velocity[b];
  const Eigen::Vector2f uv = (1.0F - t) * rest_uv[a] + t * rest_uv[b];
  const bool fixed = inverse_mass[a] == 0.0F && inverse_mass[b] == 0.0F;
  const bool is_pinned = pinned[a] != 0 && pinned[b] != 0;
  position.push_back(x);
  velocity.push_back(vel);
  rest_uv.push_back(uv);
  grid.push_back({static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y()))});
  pinned.push_back(is_pinned ? 1 : 0);
  mass.push_back(new_mass);
  inverse_mass.push_back(fixed ? 0.0F : 1.0F / new_mass);
  spring_incidence_.emplace_back();
  triangle_incidence_.emplace_back();
  ++topology_version;
  return p;
}

void Cloth::set_mass(std::size_t i, float new_mass) {
  mass[i] = new_mass;
  if (inverse_mass[i] != 0.0F) inverse_mass[i] = 1.0F / new_mass;
}

float Cloth::rest_distance(std::size_t i, std::size_t j) const {
  const float dx = (rest_uv[i].x() - rest_uv[j].x()) * spacing_x_;
  const float dy = (rest_uv[i].y() - rest_uv[j].y()) * spacing_y_;
  return std::sqrt(dx * dx + dy * dy);
}

float Cloth::grid_rest_length(GridCoord a, GridCoord b) const {
  const float dx = static_cast<float>(a.u - b.u) * spacing_x_;
  const float dy = static_cast<float>(a.v - b.v) * spacing_y_;
  return std::sqrt(dx * dx + dy * dy);
}

std::uint32_t Cloth::add_spring(std::uint32_t a, std::uint32_t b, SpringKind spring_kind) {
  const auto k = static_cast<std::uint32_t>(spring_a.size());
  spring_a.push_back(a);
  spring_b.push_back(b);
  rest_length.push_back(rest_distance(a, b));
  kind.push_back(spring_kind);
  alive.push_back(1);
  spring_incidence_[a].push_back(k);
  spring_incidence_[b].push_back(k);
  spring_edits.push_back(k);
  ++topology_version;
  return k;
}

void Cloth::remove_spring(std::uint32_t k) {
  if (alive[k] == 0) return;
  alive[k] = 0;
  spring_incidence_[spring_a[k]].erase(k);
  spring_incidence_[spring_b[k]].erase(k);
  spring_edits.push_back(k);
  ++topology_version;
}

bool Cloth::rewire_spring(std::uint32_t k, std::uint32_t old_endpoint, std::uint32_t new_endpoint) {
  std::uint32_t* end = spring_a[k] == old_endpoint ? &spring_a[k] : spring_b[k] == old_endpoint ? &spring_b[k] : nullptr;
  if (end == nullptr) return false;
  *end = new_endpoint;
  spring_edits.push_back(k);
  if (alive[k] != 0) {
    spring_incidence_[old_endpoint].erase(k);
    spring_incidence_[new_endpoint].push_back(k);
  }
  ++topology_version;
  return true;
}

std::uint32_t Cloth::add_triangle(std::array<std::uint32_t, 3> vertices) {
  const auto t = static_cast<std::uint32_t>(triangles.size());
  triangles.push_back(vertices);
  triangle_alive.push_back(1);
  for (const std::uint32_t p : vertices) triangle_incidence_[p].push_back(t);
  ++topology_version;
  return t;
}

void Cloth::remove_triangle(std::uint32_t t) {
  if (triangle_alive[t] == 0) return;
  triangle_alive[t] = 0;
  for (const std::uint32_t p : triangles[t]) triangle_incidence_[p].erase(t);
  ++topology_version;
}

bool Cloth::rewire_triangle(std::uint32_t t, std::uint32_t old_vertex, std::uint32_t new_vertex) {
  auto& tri = triangles[t];
  const auto it = std::find(tri.begin(), tri.end(), old_vertex);
  if (it == tri.end()) return false;
  *it = new_vertex;
  if (triangle_alive[t] != 0) {
    triangle_incidence_[old_vertex].erase(t);
    triangle_incidence_[new_vertex].push_back(t);
  }
  ++topology_version;
  return true;
}

void Cloth::set_pinned(std::size_t i, bool is_pinned) {
  pinned[i] = is_pinned ? 1 : 0;
  inverse_mass[i] = is_pinned ? 0.0F : 1.0F / mass[i];
  if (is_pinned) velocity[i].setZero();
}

float Cloth::max_structural_strain() const {
  float worst = 0.0F;
  for (std::size_t k = 0; k < spring_a.size(); ++k) {
    if (alive[k] == 0 || kind[k] != SpringKind::Structural) continue;
    const float len = (position[spring_a[k]] - position[spring_b[k]]).norm();
    worst = std::max(worst, len / rest_length[k] - 1.0F);
  }
  return worst;
}

}  // namespace tachi::sim
