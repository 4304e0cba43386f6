// The solver a session runs, chosen by --solver: the default position-based Solver (solver.hpp) or
// Provot's explicit mass-spring scheme (provot_solver.hpp), both set from one Material.
#pragma once

#include "tachi/sim/collision.hpp"
#include "tachi/sim/material.hpp"
#include "tachi/sim/provot_solver.hpp"
#include "tachi/sim/solver.hpp"

#include <optional>
#include <string_view>
#include <variant>

namespace tachi::sim {

enum class SolverKind : std::uint8_t { Pbd, Provot };

/// "pbd", "provot"; nothing for anything else.
[[nodiscard]] std::optional<SolverKind> parse_solver_kind(std::string_view name);
[[nodiscard]] std::string_view to_string(SolverKind kind);

/// Puts a material into the solver parameters and the cloth: total mass = mass per area x area; for the
/// position-based solver the XPBD compliances are the inverse spring constants of the grid (alpha = 1/k,
/// Macklin et al. 2016) and the air damping is the material's.
void apply_material(const Material& material, ClothConfig& cloth, SolverParams& pbd);

class ClothSolver {
 public:
  ClothSolver(SolverKind kind, const SolverParams& pbd, const ProvotParams& provot);
  explicit ClothSolver(const SolverParams& pbd = {}) : solver_(Solver{pbd}) {}

  void step(Cloth& cloth, const Colliders& colliders = {});
  /// Builds the position-based solver's caches now (Solver::prepare), so the first step is an ordinary
  /// one; Provot's solver keeps none.
  void prepare(const Cloth& cloth);
  [[nodiscard]] float dt() const;
  /// Whether the position-based solver's tether work after a cut is still going on (Solver::repairing);
  /// Provot's solver has none.
  [[nodiscard]] bool repairing() const;
  [[nodiscard]] SolverKind kind() const { return solver_.index() == 0 ? SolverKind::Pbd : SolverKind::Provot; }

 private:
  std::variant<Solver, ProvotSolver> solver_;
};

}  // namespace tachi::sim
