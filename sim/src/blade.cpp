#include "tachi/sim/blade.hpp"

#include <array>
#include <cmath>

namespace tachi::sim {

namespace {

struct BladeRow {
  Blade blade;
  std::string_view name;
  Sharpness sharpness;
};

// Seed 001 Figure 4.
constexpr std::array<BladeRow, 6> kBlades{{
    {Blade::Razor, "razor", {0.3F, 0.4F}},
    {Blade::Scalpel, "scalpel", {0.4F, 0.6F}},
    {Blade::Utility, "utility", {1.0F, 1.4F}},
    {Blade::Kitchen, "kitchen", {1.8F, 3.0F}},
    {Blade::Hunting, "hunting", {1.9F, 3.5F}},
    {Blade::Worn, "worn", {6.0F, 11.0F}},
}};

}  // namespace

Sharpness sharpness(Blade blade) { return kBlades[static_cast<std::size_t>(blade)].sharpness; }

std::string_view to_string(Blade blade) { return kBlades[static_cast<std::size_t>(blade)].name; }

std::optional<Blade> parse_blade(std::string_view name) {
  for (const BladeRow& row : kBlades) {
    if (row.name == name) return row.blade;
  }
  return std::nullopt;
}

void apply_blade_drag(Cloth& cloth, std::span<const std::uint32_t> cut_particles, const Eigen::Vector3f& direction,
                      Blade blade, const BladeDrag& drag, BladeScratch& scratch) {
  const float norm = direction.norm();
  if (!(norm > 0.0F) || !std::isfinite(norm) || cut_particles.empty()) return;
  const Eigen::Vector3f unit = direction / norm;
  const float force = sharpness(blade).force_n();
  const float reach = drag.radius_cells(force) + 1.0F;
  auto& weight = scratch.weight;
  auto& queue = scratch.queue;
  auto& touched = scratch.touched;
  if (weight.size() < cloth.particle_count()) weight.resize(cloth.particle_count(), 0.0F);
  queue.clear();
  touched.clear();

  // Breadth-first from all cut particles at once through live springs: each particle is reached once, from
  // the nearest cut particle (in springs), and weighs 1 - d / reach, d its grid distance to that particle.
  for (const std::uint32_t p : cut_particles) {
    if (p >= cloth.particle_count()) continue;
    if (weight[p] == 0.0F) touched.push_back(p);
    weight[p] = 1.0F;
    queue.push_back({p, cloth.grid[p]});
  }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const BladeScratch::Item item = queue[head];
    for (const std::uint32_t k : cloth.springs_of(item.particle)) {
      if (cloth.kind[k] != SpringKind::Structural) continue;  // diagonals reach nothing the grid does not
      const std::uint32_t q = cloth.spring_a[k] == item.particle ? cloth.spring_b[k] : cloth.spring_a[k];
      const float du = static_cast<float>(cloth.grid[q].u - item.source.u);
      const float dv = static_cast<float>(cloth.grid[q].v - item.source.v);
      if (weight[q] != 0.0F) continue;
      const float w = 1.0F - std::sqrt(du * du + dv * dv) / reach;
      if (w <= 0.0F) continue;
      touched.push_back(q);
      weight[q] = w;
      queue.push_back({q, item.source});
    }
  }
  const float peak = std::min(drag.gain_mps_per_n * force, drag.max_speed_mps);
  for (const std::uint32_t p : touched) {
    if (cloth.inverse_mass[p] > 0.0F) cloth.velocity[p] += (peak * weight[p]) * unit;
    weight[p] = 0.0F;
  }
}

}  // namespace tachi::sim
