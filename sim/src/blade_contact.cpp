#include "tachi/sim/blade_contact.hpp"

#include "tachi/sim/grab.hpp"

#include <algorithm>

namespace tachi::sim {

float contact_force(const Cloth& cloth, std::uint32_t i, const SpringStiffness& k) {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const std::uint32_t s : cloth.springs_of(i)) {
    if (cloth.alive[s] == 0 || cloth.kind[s] == SpringKind::Bend) continue;
    const std::uint32_t j = cloth.spring_a[s] == i ? cloth.spring_b[s] : cloth.spring_a[s];
    const Eigen::Vector3f d = cloth.position[j] - cloth.position[i];
    const float len = d.norm();
    const float stretch = len - cloth.rest_length[s];
    if (stretch <= 0.0F || len < 1e-9F) continue;
    const float ks = cloth.kind[s] == SpringKind::Structural ? k.structural : k.shear;
    sum += (ks * stretch / len) * d;
  }
  return sum.norm();
}

BladeContact::Verdict BladeContact::press(Cloth& cloth, const Eigen::Vector3f& hand) {
  if (!hand.allFinite()) return Verdict::Away;
  if (through_) {
    // Through the cloth the blade slices on at the hand's pace while it is in the cloth; once it has
    // left it (nothing within reach), the next contact must penetrate again.
    if (nearest_particle(cloth, hand, params_.reach_m)) return Verdict::Cutting;
    through_ = false;
    return Verdict::Away;
  }
  if (held_ && *held_ >= cloth.particle_count()) held_.reset();
  if (!held_) {
    const auto met = nearest_particle(cloth, hand, params_.reach_m);
    if (!met) return Verdict::Away;
    // A pinned particle does not give way: the blade's whole push is on it.
    if (cloth.pinned[*met] != 0) {
      cut_ = through_ = true;
      return Verdict::Cutting;
    }
    held_ = met;
    offset_ = cloth.position[*met] - hand;
    met_at_ = cloth.position[*met];
    cloth.inverse_mass[*met] = 0.0F;
    cloth.velocity[*met].setZero();
  }
  const std::uint32_t i = *held_;
  cloth.position[i] = hand + offset_;
  drag_m_ = std::max(drag_m_, (cloth.position[i] - met_at_).norm());
  const float force = contact_force(cloth, i, params_.stiffness);
  max_force_n_ = std::max(max_force_n_, force);
  if (force < params_.force_n) return Verdict::Pushing;
  // Penetrated (seed 001: sharpness is the force a blade needs to penetrate): this sample cuts.
  let_go(cloth);
  cut_ = through_ = true;
  return Verdict::Cutting;
}

void BladeContact::let_go(Cloth& cloth) {
  if (!held_) return;
  const std::uint32_t i = *held_;
  held_.reset();
  if (i < cloth.particle_count()) cloth.set_pinned(i, cloth.pinned[i] != 0);
}

void BladeContact::end_stroke(Cloth& cloth) {
  let_go(cloth);
  cut_ = through_ = false;
  max_force_n_ = 0.0F;
  drag_m_ = 0.0F;
}

}  // namespace tachi::sim
