#include "tachi/sim/grab.hpp"

namespace tachi::sim {

std::optional<std::uint32_t> nearest_particle(const Cloth& cloth, const Eigen::Vector3f& p, float max_distance) {
  if (!p.allFinite()) return std::nullopt;
  std::optional<std::uint32_t> best;
  float best_d2 = max_distance * max_distance;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.springs_of(i).empty() && cloth.triangles_of(i).empty()) continue;
    const float d2 = (cloth.position[i] - p).squaredNorm();
    if (d2 <= best_d2) {
      if (d2 == best_d2 && best) continue;  // ties go to the lower index: deterministic
      best_d2 = d2;
      best = static_cast<std::uint32_t>(i);
    }
  }
  return best;
}

std::optional<std::uint32_t> Grab::grab(Cloth& cloth, const Eigen::Vector3f& hand, float max_distance) {
  if (held_) return held_;
  held_ = nearest_particle(cloth, hand, max_distance);
  if (held_) {
    cloth.inverse_mass[*held_] = 0.0F;
    cloth.velocity[*held_].setZero();
  }
  return held_;
}

void Grab::move(Cloth& cloth, const Eigen::Vector3f& hand, float dt) {
  if (!held_ || *held_ >= cloth.particle_count() || !hand.allFinite()) return;
  Eigen::Vector3f& p = cloth.position[*held_];
  cloth.velocity[*held_] = dt > 0.0F ? Eigen::Vector3f{(hand - p) / dt} : Eigen::Vector3f::Zero();
  p = hand;
}

void Grab::release(Cloth& cloth) {
  if (!held_) return;
  const std::uint32_t i = *held_;
  held_.reset();
  if (i >= cloth.particle_count()) return;
  cloth.set_pinned(i, cloth.pinned[i] != 0);
}

}  // namespace tachi::sim
