// Blade sharpness (seed 001 section 2.1, Figure 4, from McCarthy et al. 2005): the force a blade needs to
// part the material. A sharp blade cuts with little force; a dull one "would require a stronger force and
// notably affect neighboring particles". The seed changes "the force applied to a cloth particle during a
// cut depending on the blade parameter" without giving the formula; ours is in apply_blade_drag.
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cutting.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace tachi::sim {

enum class Blade : std::uint8_t { Razor, Scalpel, Utility, Kitchen, Hunting, Worn };

/// Figure 4 of seed 001: typical sharpness range of a blade, newtons.
struct Sharpness {
  float min_n;
  float max_n;
  /// The force a cut with this blade applies: the middle of the range.
  [[nodiscard]] float force_n() const { return 0.5F * (min_n + max_n); }
};

[[nodiscard]] Sharpness sharpness(Blade blade);
/// "razor", "scalpel", "utility", "kitchen", "hunting", "worn"; nothing for anything else.
[[nodiscard]] std::optional<Blade> parse_blade(std::string_view name);
[[nodiscard]] std::string_view to_string(Blade blade);

/// How the blade force drags the cloth. Velocity change of a particle at grid distance d from the particle
/// being cut: gain * F * (1 - d / (radius + 1)) along the blade's motion, radius = 1 + F / 2 N cells, capped
/// at max_speed. The force grows both the push and the reach, so a worn blade (8.5 N) drags a patch five
/// cells wide at ~0.85 m/s while a razor (0.35 N) barely moves the particle it cuts.
struct BladeDrag {
  float gain_mps_per_n = 0.1F;
  float max_speed_mps = 1.5F;
  [[nodiscard]] float radius_cells(float force_n) const { return 1.0F + 0.5F * force_n; }
};

/// Working memory of apply_blade_drag, reused between calls (no allocation in steady state).
struct BladeScratch {
  std::vector<float> weight;  // per particle, 0 outside the current call
  std::vector<std::uint32_t> touched;
  std::vector<std::uint32_t> copies;
};

/// Applies the drag of `blade` cutting through the grid points `cut_points` while moving along `direction`
/// (world, any length; a zero direction does nothing): every particle of the grid patch around them (all
/// copies of a grid point: the blade drags both lips of the cut) gets the velocity change of BladeDrag.
/// The patch is walked on the grid, not through springs, so the cost is a few velocity writes per point.
/// Pinned particles do not move.
void apply_blade_drag(Cloth& cloth, const ClothCutter& cutter, std::span<const GridCoord> cut_points,
                      const Eigen::Vector3f& direction, Blade blade, const BladeDrag& drag, BladeScratch& scratch);

}  // namespace tachi::sim
