// The randomized world: a scenario drawn from distributions instead of a hand-written script, so
// that the hand finder is evaluated (and tuned) on scenes nobody looked at. One seed, one clip.
//
// What is drawn (docs/sensor.md, "Randomized world", gives the ranges and why):
//  - the user: distance 0.8-2.5 m, sideways place, height, left or right handed, arm length;
//  - the room: the back wall's depth; 0-4 objects (box, table edge, chair back, monitor, side
//    wall), some nearer than the hand, some across the image edge, there from frame 0 or moved in;
//  - a second person walking behind or standing behind;
//  - the start: hand up from frame 0, raised later, or never raised; the path: sweeps, curves,
//    pushes toward the camera, zig-zags, pauses, leaving the image and coming back, tremor of
//    random amplitude and frequency, palm yaw up to 60 degrees;
//  - Kinect v1 noise: disparity noise, edge dropouts, dropout blobs (quantisation and IR shadows
//    are rendered by SyntheticScene for every clip).
// Seeds 1-1000 are the tuning range; 100001 and up are held out (no threshold looked at them).
#pragma once

#include <cstdint>

#include "tachi/sensor/synthetic.hpp"

namespace tachi::sensor {

/// The start condition of a clip.
enum class HandStart { kUpFromFirstFrame, kRaisedLater, kNeverRaised };

/// Draws the scenario of `seed` (deterministic: the same seed gives the same clip on every machine
/// with the same standard library, since only std::mt19937_64 draws are used, through our own
/// uniform mapping rather than the library's distributions). `hanging_rest` (the default since
/// session 35): the hand rests at the arm's end, fingers down (ScenarioSpec::hanging_rest). False: the
/// previous world's floating resting pose beyond the arm's reach, physically impossible, kept to compare
/// with earlier figures (the same draws, so the same room, user and path; docs/sensor.md).
ScenarioSpec random_scenario(std::uint64_t seed, bool hanging_rest = true);

/// The start condition random_scenario(seed) drew (for reports).
HandStart random_start(const ScenarioSpec& spec);

}  // namespace tachi::sensor
