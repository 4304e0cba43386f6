#include "tachi/sim/cloth_solver.hpp"

namespace tachi::sim {

std::optional<SolverKind> parse_solver_kind(std::string_view name) {
  if (name == "pbd") return SolverKind::Pbd;
  if (name == "provot") return SolverKind::Provot;
  return std::nullopt;
}

std::string_view to_string(SolverKind kind) { return kind == SolverKind::Pbd ? "pbd" : "provot"; }

void apply_material(const Material& material, ClothConfig& cloth, SolverParams& pbd) {
  cloth.total_mass_kg = material.mass_per_area_kg_m2 * cloth.width_m * cloth.height_m;
  const float spacing_x = cloth.width_m / static_cast<float>(std::max(cloth.columns - 1, 1));
  const float spacing_y = cloth.height_m / static_cast<float>(std::max(cloth.rows - 1, 1));
  const SpringStiffness k = spring_stiffness(material, spacing_x, spacing_y);
  pbd.structural_compliance = 1.0F / k.structural;
  pbd.shear_compliance = 1.0F / k.shear;
  pbd.bend_compliance = 1.0F / k.bend;
  pbd.damping = material.damping_per_s;
}

ClothSolver::ClothSolver(SolverKind kind, const SolverParams& pbd, const ProvotParams& provot)
    : solver_(kind == SolverKind::Pbd ? std::variant<Solver, ProvotSolver>{Solver{pbd}}
                                      : std::variant<Solver, ProvotSolver>{ProvotSolver{provot}}) {}

void ClothSolver::step(Cloth& cloth, const Colliders& colliders) {
  std::visit([&](auto& solver) { solver.step(cloth, colliders); }, solver_);
}

void ClothSolver::prepare(const Cloth& cloth) {
  if (auto* pbd = std::get_if<Solver>(&solver_)) pbd->prepare(cloth);
}

bool ClothSolver::repairing() const {
  const auto* pbd = std::get_if<Solver>(&solver_);
  return pbd != nullptr && pbd->repairing();
}

float ClothSolver::dt() const {
  return std::visit([](const auto& solver) { return solver.params().dt; }, solver_);
}

}  // namespace tachi::sim
