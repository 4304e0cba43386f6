// Cloth materials: the physical quantities a fabric brings to the mass-spring model (Provot 1995; seed 001
// section 2.1 uses stiffness k and mass m per particle). Values per unit area and width, so one material
// means the same cloth on every grid; spring_stiffness() turns them into the springs of a given grid.
// Preset values and their sources: docs/sim.md, "Materials".
#pragma once

#include "tachi/sim/cloth.hpp"

#include <optional>
#include <string>
#include <string_view>

namespace tachi::sim {

struct Material {
  float mass_per_area_kg_m2 = 0.15F;  ///< areal density (a 1 m^2 cloth weighs this many kg)
  float stretch_n_per_m = 800.0F;     ///< tensile stiffness per unit width: force per metre of width per unit strain
  float shear_n_per_m = 60.0F;        ///< in-plane shear stiffness per unit width (N/m per radian)
  float bend_n_m = 1e-5F;             ///< bending rigidity (N m: moment per metre of width per unit curvature)
  float damping_per_s = 0.5F;         ///< velocity damping (air drag), 1/s
};

/// "cotton", "silk", "denim", "felt"; nothing for anything else.
[[nodiscard]] std::optional<Material> material_preset(std::string_view name);
/// The names material_preset() knows, comma separated, for help texts and errors.
[[nodiscard]] std::string_view material_names();

/// Checks every field is finite and in its physical range; the message names the flag
/// (--mass-per-area, --stretch-stiffness, --shear-stiffness, --bend-stiffness, --damping) and the range.
[[nodiscard]] std::optional<std::string> validate(const Material& material);

/// Spring constants (N/m) of a grid of `cloth`'s spacing. Structural: a spring along x carries a strip
/// of width spacing_y, so k = E spacing_y / spacing_x (E = stretch per width). Shear: k = G (one diagonal
/// spring per cell and direction, its strip as wide as it is long). Bend: a bend spring spanning 2 cells
/// resists a curvature kappa with a moment B kappa per width; the small-angle length change of the span
/// gives k = 4 B / spacing^2 per strip width spacing, i.e. k = 4 B / spacing^2 (documented approximation).
struct SpringStiffness {
  float structural = 0.0F;
  float shear = 0.0F;
  float bend = 0.0F;
};
[[nodiscard]] SpringStiffness spring_stiffness(const Material& material, float spacing_x, float spacing_y);

}  // namespace tachi::sim
