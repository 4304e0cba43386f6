#include "tachi/sim/material.hpp"

#include <array>
#include <cmath>

namespace tachi::sim {

namespace {

struct MaterialRow {
  std::string_view name;
  Material material;
};

// Representative values of the four fabrics (docs/sim.md gives the sources and the unit conversions):
// areal density from typical fabric weights (g/m^2), stretch and shear from KES-F tensile and shear
// measurements at low strain, bending rigidity from KES-F B (gf cm^2/cm, 1 gf cm^2/cm = 9.8e-5 N m).
constexpr std::array<MaterialRow, 4> kMaterials{{
    {"cotton", {0.15F, 800.0F, 60.0F, 8e-6F, 0.5F}},
    {"silk", {0.06F, 400.0F, 20.0F, 1.5e-6F, 0.8F}},
    {"denim", {0.40F, 3000.0F, 170.0F, 6e-5F, 0.4F}},
    {"felt", {0.30F, 150.0F, 250.0F, 1.5e-4F, 0.6F}},
}};

bool in(float value, float lo, float hi) { return std::isfinite(value) && value >= lo && value <= hi; }

}  // namespace

std::optional<Material> material_preset(std::string_view name) {
  for (const MaterialRow& row : kMaterials) {
    if (row.name == name) return row.material;
  }
  return std::nullopt;
}

std::string_view material_names() { return "cotton, silk, denim, felt"; }

std::optional<std::string> validate(const Material& m) {
  if (!in(m.mass_per_area_kg_m2, 0.005F, 5.0F)) return "--mass-per-area must be in [0.005, 5] kg/m^2";
  if (!in(m.stretch_n_per_m, 1.0F, 1e6F)) return "--stretch-stiffness must be in [1, 1e6] N/m";
  if (!in(m.shear_n_per_m, 0.01F, 1e6F)) return "--shear-stiffness must be in [0.01, 1e6] N/m";
  if (!in(m.bend_n_m, 1e-9F, 1.0F)) return "--bend-stiffness must be in [1e-9, 1] N m";
  if (!in(m.damping_per_s, 0.0F, 100.0F)) return "--damping must be in [0, 100] 1/s";
  return std::nullopt;
}

SpringStiffness spring_stiffness(const Material& m, float spacing_x, float spacing_y) {
  const float spacing = 0.5F * (spacing_x + spacing_y);
  SpringStiffness k;
  k.structural = m.stretch_n_per_m * spacing_y / spacing_x;
  k.shear = m.shear_n_per_m;
  k.bend = 4.0F * m.bend_n_m / (spacing * spacing);
  return k;
}

}  // namespace tachi::sim
