// Blade sharpness decides the cut (seed 001 section 2.1, Figure 4 after McCarthy et al. 2005): a blade
// parts the cloth only when it presses on it with at least its sharpness force; below that the hand is a
// pusher and drags the cloth along. This is the decision in front of the StrokeCutter.
//
// The contact: within `reach_m` of the cloth the blade meets the particle nearest to it and holds it as a
// kinematic point (like a grab: inverse mass 0) that moves with the hand, so the solver resolves the rest
// of the cloth against it. The contact force is the cloth's response on that particle: the vector sum of
// its structural and shear spring tensions, F = | sum_k k_k max(0, |x_j - x_i| - L_k) u_k |, with the
// material's spring constants (material.hpp), measured after the blade has moved it to the hand. A taut
// region answers a small motion with a large force (a razor cuts at once); a loose flap follows the hand
// and never reaches a worn blade's 8.5 N.
// docs/cutting.md, "Blade sharpness decides the cut (`--blade NAME`, `--blade-force N`)".
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/material.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>

namespace tachi::sim {

/// Net force (N) the structural and shear springs of particle i pull on it with, springs stretched
/// beyond their rest length only (cloth does not push back when compressed).
[[nodiscard]] float contact_force(const Cloth& cloth, std::uint32_t i, const SpringStiffness& k);

struct BladeContactParams {
  float force_n = 0.5F;   ///< the blade's sharpness force (seed 001 Figure 4)
  float reach_m = 0.06F;  ///< the blade meets the cloth within this distance of a particle
  SpringStiffness stiffness;  ///< the cloth's springs, for contact_force
};

class BladeContact {
 public:
  enum class Verdict : std::uint8_t {
    Away,     ///< not touching the cloth: nothing happens
    Pushing,  ///< touching below the sharpness force: the cloth is dragged, not cut
    Cutting,  ///< the blade is through: the sample cuts
  };

  explicit BladeContact(const BladeContactParams& params) : params_(params) {}

  /// One sample of a cutting stroke. Until the blade is through, it meets the nearest particle within
  /// reach (or keeps the one it holds), moves it with the hand and measures the contact force: at or
  /// above the sharpness force it penetrates (the sample cuts, the particle is let go); below, it drags
  /// the particle. A pinned particle does not give way: the sample cuts. Through the cloth the blade
  /// slices on (seed 001: sharpness is the force to penetrate) until a sample finds no cloth within reach.
  Verdict press(Cloth& cloth, const Eigen::Vector3f& hand);
  /// The stroke ended (or paused): the held particle goes back to the dynamics.
  void let_go(Cloth& cloth);
  /// let_go and forget the stroke: the next press starts a new one.
  void end_stroke(Cloth& cloth);

  /// Some sample of this stroke has cut.
  [[nodiscard]] bool has_cut() const { return cut_; }
  [[nodiscard]] std::optional<std::uint32_t> held() const { return held_; }
  /// Largest contact force and largest drag (distance the blade moved a held particle) of the stroke.
  [[nodiscard]] float max_force_n() const { return max_force_n_; }
  [[nodiscard]] float drag_m() const { return drag_m_; }
  [[nodiscard]] const BladeContactParams& params() const { return params_; }

 private:
  BladeContactParams params_;
  bool cut_ = false;
  bool through_ = false;
  std::optional<std::uint32_t> held_;
  Eigen::Vector3f offset_ = Eigen::Vector3f::Zero();  ///< held particle - hand, fixed when met
  Eigen::Vector3f met_at_ = Eigen::Vector3f::Zero();  ///< the held particle's position when met
  float max_force_n_ = 0.0F;
  float drag_m_ = 0.0F;
};

}  // namespace tachi::sim
