// Cloth handling by hand (seed 000 section 2, Mesuda et al.): the hand takes the particle nearest to it,
// that particle follows the hand as a kinematic point (inverse mass 0) and is given back to the
// dynamics, with the hand's last velocity, when the hand releases it.
#pragma once

#include "tachi/sim/cloth.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <optional>

namespace tachi::sim {

/// Index of the live particle nearest to p (a particle with at least one live spring or triangle, so
/// an isolated leftover of a cut is never picked), or nothing if there is none within max_distance.
[[nodiscard]] std::optional<std::uint32_t> nearest_particle(const Cloth& cloth, const Eigen::Vector3f& p,
                                                            float max_distance = std::numeric_limits<float>::infinity());

class Grab {
 public:
  /// Takes the particle nearest to `hand` if it lies within max_distance; returns it. Already holding:
  /// the held particle is kept (one hand holds one point).
  std::optional<std::uint32_t> grab(Cloth& cloth, const Eigen::Vector3f& hand,
                                    float max_distance = std::numeric_limits<float>::infinity());
  /// Moves the held particle to `hand`; its velocity becomes the hand's over `dt`. No-op when empty.
  void move(Cloth& cloth, const Eigen::Vector3f& hand, float dt);
  /// Gives the held particle back to the dynamics (a pinned particle stays pinned).
  void release(Cloth& cloth);

  [[nodiscard]] std::optional<std::uint32_t> held() const { return held_; }

 private:
  std::optional<std::uint32_t> held_;
};

}  // namespace tachi::sim
