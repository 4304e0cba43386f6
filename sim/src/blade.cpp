#include "tachi/sim/blade.hpp"

#include <algorithm>
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

void apply_blade_drag(Cloth& cloth, const ClothCutter& cutter, std::span<const GridCoord> cut_points,
                      const Eigen::Vector3f& direction, Blade blade, const BladeDrag& drag, BladeScratch& scratch) {
  const float norm = direction.norm();
  if (!(norm > 0.0F) || !std::isfinite(norm) || cut_points.empty()) return;
  const Eigen::Vector3f unit = direction / norm;
  const float force = sharpness(blade).force_n();
  const float reach = drag.radius_cells(force) + 1.0F;
  const int box = static_cast<int>(reach);
  auto& weight = scratch.weight;
  auto& touched = scratch.touched;
  if (weight.size() < cloth.particle_count()) weight.resize(cloth.particle_count(), 0.0F);
  touched.clear();
  // Each particle of the patch weighs 1 - d / reach, d its grid distance to the nearest cut point.
  for (const GridCoord g : cut_points) {
    for (int dv = -box; dv <= box; ++dv) {
      for (int du = -box; du <= box; ++du) {
        const float w = 1.0F - std::sqrt(static_cast<float>(du * du + dv * dv)) / reach;
        if (w <= 0.0F) continue;
        scratch.copies.clear();
        cutter.append_copies({g.u + du, g.v + dv}, scratch.copies);
        for (const std::uint32_t p : scratch.copies) {
          if (weight[p] == 0.0F) touched.push_back(p);
          weight[p] = std::max(weight[p], w);
        }
      }
    }
  }
  const float peak = std::min(drag.gain_mps_per_n * force, drag.max_speed_mps);
  for (const std::uint32_t p : touched) {
    if (cloth.inverse_mass[p] > 0.0F) cloth.velocity[p] += (peak * weight[p]) * unit;
    weight[p] = 0.0F;
  }
}

}  // namespace tachi::sim
