// Synthetic hand trajectories for the filter tests, in the camera frame (x right, y down, z forward).
#pragma once

#include "tachi/filter/types.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <ostream>
#include <random>
#include <vector>

namespace tachi::filter::testing {

/// A hand that pushes toward the sensor until it nearly touches the cloth plane (1.0 m from the sensor),
/// cuts sideways while hovering 4 cm in front of it, and pulls back. As seed 000 section 5 describes, the
/// hand fluctuates while the user adjusts its distance to the cloth: an in-and-out sway (1.5 cm, 2 Hz)
/// plus jitter (sigma `wobble_m` per axis). The user slows down near the cloth, so it lingers near any
/// threshold. 30 Hz.
inline std::vector<HandSample> push_and_back(unsigned seed = 1, float wobble_m = 0.006F, int frames = 120) {
  std::mt19937 rng{seed};
  std::normal_distribution<float> wobble{0.0F, wobble_m};
  const float phase = std::uniform_real_distribution<float>{0.0F, 6.2831853F}(rng);
  std::vector<HandSample> hands;
  for (int i = 0; i < frames; ++i) {
    const float s = static_cast<float>(i) / static_cast<float>(frames - 1);
    HandSample h;
    h.frame = static_cast<std::uint64_t>(i);
    h.stamp_ns = 1'000'000'000LL + static_cast<std::int64_t>(i) * 33'333'333LL;
    // 0.30 m in front of the cloth -> 0.04 m (eased in and out over the first and last 40%) -> back,
    // drifting from the user's right to left.
    const auto smoothstep = [](float t) { t = std::clamp(t, 0.0F, 1.0F); return t * t * (3.0F - 2.0F * t); };
    const float reach = std::min(smoothstep(s / 0.4F), smoothstep((1.0F - s) / 0.4F));
    const float t = static_cast<float>(i) / 30.0F;
    const float sway = 0.015F * reach * std::sin(2.0F * std::numbers::pi_v<float> * 2.0F * t + phase);
    const float depth = 1.30F - 0.26F * reach + sway;
    h.position_m = {-0.1F + 0.2F * s + wobble(rng), 0.05F + wobble(rng), depth + wobble(rng)};
    h.tracked = true;
    h.confidence = 0.9F;
    hands.push_back(h);
  }
  return hands;
}

inline void write_hand_csv(std::ostream& out, const std::vector<HandSample>& hands) {
  out << "frame,stamp_ns,x,y,z,u,v,tracked,confidence\n";
  for (const auto& h : hands)
    out << h.frame << ',' << h.stamp_ns << ',' << h.position_m.x() << ',' << h.position_m.y() << ','
        << h.position_m.z() << ",320,240," << (h.tracked ? 1 : 0) << ',' << h.confidence << '\n';
}

}  // namespace tachi::filter::testing
