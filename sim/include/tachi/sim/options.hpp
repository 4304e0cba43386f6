// What a simulation is asked for (the cloth, solver, material, blade, cut mode, shapes, object, stroke file, export
// folder), shared by tachi-sim's live and offline modes; the session those options describe; and the checks made
// when the options are parsed (grid sizes, memory). The flags that fill it are the executable's (sim/flags.cpp).
#pragma once

#include "tachi/sim/blade.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cloth_solver.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/material.hpp"
#include "tachi/sim/session.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tachi::sim {

struct OfflineOptions {
  ClothConfig cloth;                    ///< --grid, --size-m, --pin
  SolverParams solver;                  ///< --substeps, --iterations
  int steps = 600;                      ///< --steps
  std::filesystem::path export_dir;     ///< --export; empty = summary on stdout only
  std::uint32_t seed = 1;               ///< --seed: out-of-plane jitter that breaks the grid's symmetry
  float jitter_m = 1e-4F;               ///< amplitude of that jitter (0 = perfectly flat start)
  std::vector<Sphere> spheres;          ///< --sphere X Y Z R (repeatable)
  std::optional<GroundPlane> ground;    ///< --ground Y
  std::filesystem::path stroke_file;    ///< --stroke: CSV t,x,y,z cut while stepping (t = seconds from the start)
  Blade blade = Blade::Scalpel;         ///< --blade
  CutMode cut_mode = CutMode::Exact;    ///< --cut-mode (the product's default; grid reproduces seed 000)
  std::optional<float> blade_force_n;   ///< --blade-force: overrides the blade's sharpness force
  SolverKind solver_kind = SolverKind::Pbd;  ///< --solver
  bool substeps_given = false;          ///< --substeps was given (else each solver's own default)
  /// --material and --mass-per-area, --stretch-stiffness, --shear-stiffness, --bend-stiffness, --damping;
  /// nothing: the position-based solver keeps its tuned defaults (Provot's solver uses Material{}).
  std::optional<Material> material;
  std::shared_ptr<const PointCloudCollider> object;  ///< --object / --object-from-recording (loaded by main)
};

/// The session the options describe (cloth, solver, material, blade, object), for offline and live runs.
[[nodiscard]] SessionOptions session_options(const OfflineOptions& options);

/// Parses "N" or "NxM" (columns x rows, each 2..4096). Nothing for anything else.
[[nodiscard]] std::optional<std::pair<int, int>> parse_grid(const std::string& text);

/// Peak resident bytes per particle of a tachi-sim run: 745-770 measured (maximum RSS of
/// `tachi-sim --offline --grid 512|1024 --steps 1`), rounded up (docs/reliability.md, "Bad configs").
inline constexpr double kPeakBytesPerParticle = 800.0;
/// Memory this process may still use: MemAvailable, or the address-space limit when lower (0: unknown).
[[nodiscard]] std::uint64_t available_memory_bytes();
/// Why a columns x rows cloth will not fit in memory (what it needs, what there is), or nothing.
[[nodiscard]] std::optional<std::string> memory_shortfall(int columns, int rows);

}  // namespace tachi::sim
