#include "tachi/filter/cloth_proximity.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tachi::filter {

namespace {
// A hand within the cloth in x-y and below the nearest point's z has pushed through the cloth.
float contact_distance(const Eigen::Vector3f& hand, const Eigen::Vector3f& nearest, bool outside,
                       const ClothProximityParams& params) {
  if (params.behind_cloth_is_contact && !outside && hand.z() < nearest.z()) return 0.0F;
  return (hand - nearest).norm();
}
}  // namespace

Proximity proximity_to_rest_cloth(const Eigen::Vector3f& hand, const ClothProximityParams& params) {
  const float hx = 0.5F * params.width_m;
  const float hy = 0.5F * params.height_m;
  Proximity p;
  p.nearest = {std::clamp(hand.x(), -hx, hx), std::clamp(hand.y(), -hy, hy), 0.0F};
  p.outside = std::abs(hand.x()) > hx || std::abs(hand.y()) > hy;
  p.distance_m = contact_distance(hand, p.nearest, p.outside, params);
  return p;
}

std::optional<Proximity> proximity_to_particles(const Eigen::Vector3f& hand, std::span<const float> xyz,
                                                const ClothProximityParams& params) {
  const std::size_t n = xyz.size() / 3;
  if (n == 0) return std::nullopt;
  float best = std::numeric_limits<float>::infinity();
  std::size_t best_i = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = xyz[3 * i] - hand.x();
    const float dy = xyz[3 * i + 1] - hand.y();
    const float dz = xyz[3 * i + 2] - hand.z();
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best) {
      best = d2;
      best_i = i;
    }
  }
  if (!(best < std::numeric_limits<float>::infinity())) return std::nullopt;  // every particle non-finite
  Proximity p;
  p.nearest = {xyz[3 * best_i], xyz[3 * best_i + 1], xyz[3 * best_i + 2]};
  p.outside = (hand.head<2>() - p.nearest.head<2>()).norm() > params.outside_margin_m;
  p.distance_m = contact_distance(hand, p.nearest, p.outside, params);
  return p;
}

}  // namespace tachi::filter
