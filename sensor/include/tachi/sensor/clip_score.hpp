// Scoring the hand finder on rendered clips, in memory: each frame rendered by SyntheticScene goes
// through HandFinder::find, the call tachi-sensor makes per depth frame, and is compared with the
// renderer's ground truth. Used by `tachi-sensor-eval --random FIRST..LAST` and its tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tachi/sensor/hand_finder.hpp"
#include "tachi/sensor/synthetic.hpp"

namespace tachi::sensor {

/// A tracked point is "captured" (by something that is not the hand) when it is farther than this
/// from the palm centre, or when no hand is raised at all.
inline constexpr double kCaptureDistanceM = 0.10;

struct ClipScore {
  std::uint64_t seed = 0;
  std::size_t frames = 0;
  std::size_t raised = 0;                ///< frames with the hand off its resting pose
  std::size_t visible = 0;               ///< frames with the palm visible (raised, in view, unoccluded)
  std::size_t tracked_visible = 0;       ///< ... and tracked
  std::size_t phantoms = 0;              ///< tracked while the palm is not visible (except near it while rising)
  std::size_t captured = 0;              ///< tracked > kCaptureDistanceM from the palm, or with no hand raised
  std::size_t longest_captured_run = 0;  ///< consecutive captured frames
  double rms_m = 0;                      ///< RMS 3D error over tracked visible frames (0 when there are none)
  double max_m = 0;
  double tracked_ratio() const { return visible ? static_cast<double>(tracked_visible) / static_cast<double>(visible) : 1.0; }
};

/// Adds one frame's observation and truth to a clip's score (the per-frame rule, shared by
/// score_clip and the tests). `run` is the current captured run, carried between frames.
void score_frame(const HandObservation& hand, const GroundTruth& truth, ClipScore& score, std::size_t& run, double& squared_sum);

/// Called with each frame's truth and observation (for a per-frame listing).
using FrameListener = std::function<void(const GroundTruth&, const HandObservation&)>;

/// Renders every frame of `spec` and runs a fresh HandFinder over them.
ClipScore score_clip(const ScenarioSpec& spec, const HandFinderParams& params = {}, const FrameListener& on_frame = {});

/// The acceptance rates for tracking on unseen scenes (docs/sensor.md).
struct Acceptance {
  double clip_rms_m = 0.01;          ///< a clip is good when its RMS is at most this ...
  double min_good_clips = 0.97;      ///< ... and this share of clips must be good
  double min_tracked_ratio = 0.99;   ///< over all visible frames of all clips
  std::size_t max_phantoms = 0;      ///< over all clips
  std::size_t max_captured_run = 3;  ///< no clip may have a longer captured run
};

struct Summary {
  std::size_t clips = 0;
  std::size_t good_clips = 0;           ///< RMS <= Acceptance::clip_rms_m
  double good_share = 0;
  double p50_rms_m = 0, p95_rms_m = 0, max_rms_m = 0;  ///< over clips with tracked visible frames
  std::size_t visible = 0, tracked_visible = 0;
  double tracked_ratio = 1;
  std::size_t phantoms = 0, phantom_clips = 0;
  std::size_t captured = 0, captured_clips = 0;
  std::size_t long_capture_clips = 0;  ///< clips whose longest captured run exceeds max_captured_run
  std::size_t longest_captured_run = 0;
  bool passed = false;
  std::vector<std::string> failures;    ///< one line per missed rate, with the measured figure
};

Summary summarize(const std::vector<ClipScore>& clips, const Acceptance& acceptance = {});

}  // namespace tachi::sensor
