// Provot's own cloth scheme, as both seeds use it (Provot 1995, "Deformation constraints in a mass-spring
// model to describe rigid cloth behavior", Graphics Interface; seed 001 section 2.1): an explicit
// mass-spring system followed by the deformation constraint. Per sub-step h = dt / substeps:
//   1. forces  F_i = m_i g - m_i c_air v_i + sum_springs [ k (|x_ij| - L) + c (v_ij . u_ij) ] u_ij   (Provot eq. 1-4,
//      with a viscous term along each spring) + seed 000's point-cloud repulsion
//   2. symplectic Euler  v += h F / m,  x += h v
//   3. deformation constraint: every structural or shear spring longer than (1 + max_strain) L is shortened
//      back, both ends moving half-way, or only the free end when the other is fixed (Provot section 5),
//      swept outwards from the fixed particles until none is over-stretched or the pass budget is spent
//   4. collisions by projection with friction; v = (x - x_start) / h, so the correction does not leave
//      velocities that fight it
// Explicit integration is stable only for h^2 sum_k k / m < ~2 per particle (Gershgorin bound on the
// stiffness matrix): stiffer springs than that are scaled down to it, which is the point of Provot's
// method (soft springs for stability, the constraint for the stiff behaviour). docs/sim.md compares it
// with the default position-based Solver.
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/material.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace tachi::sim {

struct ProvotParams {
  float dt = 1.0F / 60.0F;
  int substeps = 32;  ///< documented default: 32 sub-steps keep cotton on a 64 x 64 metre cloth stable
  Eigen::Vector3f gravity{0.0F, -9.81F, 0.0F};
  Material material;
  float spring_damping_ratio = 0.1F;  ///< c = ratio * 2 sqrt(k m): a fraction of each spring's critical damping
  float max_strain = 0.10F;           ///< Provot's critical deformation rate
  int correction_passes = 16;         ///< sweeps of the deformation constraint per sub-step (stops when clean)
};

/// Returns a message naming the bad field, or nothing.
[[nodiscard]] std::optional<std::string> validate(const ProvotParams& params);

class ProvotSolver {
 public:
  explicit ProvotSolver(ProvotParams params = {});

  /// Advances the cloth by params().dt.
  void step(Cloth& cloth, const Colliders& colliders = {});

  [[nodiscard]] const ProvotParams& params() const { return params_; }
  /// Spring constants in use after the stability cap (N/m), for the docs and tests.
  [[nodiscard]] const SpringStiffness& stiffness_in_use() const { return used_; }
  /// Share of the material's stiffness kept by the stability cap (1 = none removed).
  [[nodiscard]] float stiffness_scale() const { return scale_; }

 private:
  struct PackedSpring {
    std::uint32_t a;
    std::uint32_t b;
    float rest;
    float k;
    float c;
    bool limited;  ///< structural or shear: subject to the deformation constraint
  };
  void refresh(const Cloth& cloth);
  void order_outwards(const Cloth& cloth);
  void substep(Cloth& cloth, const Colliders& colliders, float h);

  ProvotParams params_;
  SpringStiffness used_;
  float scale_ = 1.0F;
  std::uint32_t cached_version_ = 0;
  std::size_t cached_springs_ = 0;
  std::size_t cached_particles_ = 0;
  bool cache_valid_ = false;
  std::vector<std::uint32_t> cached_fixed_;  ///< pinned or held particles (inverse mass 0) the order starts from
  std::vector<PackedSpring> springs_;
  std::vector<std::uint32_t> limited_;  ///< indices into springs_ of the constrained springs
  std::vector<Eigen::Vector3f> force_;
  std::vector<Eigen::Vector3f> start_;
};

}  // namespace tachi::sim
