// Hand-to-cloth distance (seed 000 section 3.1: the distance between the hand and the nearest particle
// of the cloth) and whether the hand is outside the cloth (seed 000 section 5: the hand mark changes
// colour outside the cloth).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <span>

namespace tachi::filter {

struct ClothProximityParams {
  float width_m = 1.0F;            ///< rest cloth extent in x (centred at the origin, plane z = 0)
  float height_m = 1.0F;           ///< rest cloth extent in y
  float outside_margin_m = 0.03F;  ///< nearest particle farther than this in the cloth plane: outside
  bool behind_cloth_is_contact = true;  ///< a hand pushed through the cloth counts as touching it
};

struct Proximity {
  float distance_m = 0.0F;  ///< to the nearest particle (0 when pushed through the cloth, if enabled)
  bool outside = false;     ///< the hand's projection misses the cloth
  Eigen::Vector3f nearest = Eigen::Vector3f::Zero();
};

/// Before the first cloth state: the rest cloth, a width x height rectangle in z = 0 centred at the origin.
Proximity proximity_to_rest_cloth(const Eigen::Vector3f& hand_world, const ClothProximityParams& params);

/// Against a published cloth state (x, y, z per particle, world frame). nullopt when there are no particles.
/// The user stands on the +z side: a hand with z below the nearest particle's, and within the cloth in x-y,
/// has pushed through it.
std::optional<Proximity> proximity_to_particles(const Eigen::Vector3f& hand_world, std::span<const float> xyz,
                                                const ClothProximityParams& params);

}  // namespace tachi::filter
