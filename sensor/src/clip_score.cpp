#include "tachi/sensor/clip_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tachi::sensor {

void score_frame(const HandObservation& hand, const GroundTruth& truth, ClipScore& score, std::size_t& run, double& squared_sum) {
  ++score.frames;
  if (truth.raised) ++score.raised;
  if (truth.visible) ++score.visible;
  bool captured = false;
  if (hand.tracked) {
    const double error = (hand.position_m.cast<double>() - truth.palm).norm();
    captured = !truth.raised || error > kCaptureDistanceM;
    if (truth.visible) {
      ++score.tracked_visible;
      squared_sum += error * error;
      score.max_m = std::max(score.max_m, error);
    } else if (!truth.rising || captured) {  // a hand reported on its way up, where it is, is no phantom
      ++score.phantoms;
    }
  }
  if (captured) {
    ++score.captured;
    score.longest_captured_run = std::max(score.longest_captured_run, ++run);
  } else {
    run = 0;
  }
  score.rms_m = score.tracked_visible ? std::sqrt(squared_sum / static_cast<double>(score.tracked_visible)) : 0.0;
}

ClipScore score_clip(const ScenarioSpec& spec, const HandFinderParams& params, const FrameListener& on_frame) {
  SyntheticScene scene(spec);
  HandFinder finder(DepthModel{}, params);
  ClipScore score;
  score.seed = spec.seed;
  std::size_t run = 0;
  double squared_sum = 0;
  for (std::uint64_t i = 0; i < scene.frame_count(); ++i) {
    GroundTruth truth;
    const DepthFrame frame = scene.render(i, truth);
    const HandObservation hand = finder.find(frame);
    score_frame(hand, truth, score, run, squared_sum);
    if (on_frame) on_frame(truth, hand);
  }
  return score;
}

namespace {
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  // Nearest rank (the smallest value with at least p of the values at or below it).
  const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}
std::string format(const char* f, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}
}  // namespace

Summary summarize(const std::vector<ClipScore>& clips, const Acceptance& acceptance) {
  Summary s;
  s.clips = clips.size();
  std::vector<double> rms;
  for (const auto& c : clips) {
    if (c.rms_m <= acceptance.clip_rms_m) ++s.good_clips;
    if (c.tracked_visible) rms.push_back(c.rms_m);
    s.visible += c.visible;
    s.tracked_visible += c.tracked_visible;
    s.phantoms += c.phantoms;
    s.phantom_clips += c.phantoms > 0;
    s.captured += c.captured;
    s.captured_clips += c.captured > 0;
    s.long_capture_clips += c.longest_captured_run > acceptance.max_captured_run;
    s.longest_captured_run = std::max(s.longest_captured_run, c.longest_captured_run);
  }
  s.good_share = s.clips ? static_cast<double>(s.good_clips) / static_cast<double>(s.clips) : 1.0;
  s.tracked_ratio = s.visible ? static_cast<double>(s.tracked_visible) / static_cast<double>(s.visible) : 1.0;
  s.p50_rms_m = percentile(rms, 0.5);
  s.p95_rms_m = percentile(rms, 0.95);
  s.max_rms_m = rms.empty() ? 0 : *std::max_element(rms.begin(), rms.end());
  if (s.good_share < acceptance.min_good_clips)
    s.failures.push_back(format("clips with RMS <= 1 cm: %.1f%% (target >= %.1f%%)", 100 * s.good_share, 100 * acceptance.min_good_clips));
  if (s.tracked_ratio < acceptance.min_tracked_ratio)
    s.failures.push_back(format("visible frames tracked: %.2f%% (target >= %.1f%%)", 100 * s.tracked_ratio, 100 * acceptance.min_tracked_ratio));
  if (s.phantoms > acceptance.max_phantoms)
    s.failures.push_back(format("phantom frames: %.0f (target <= %.0f)", static_cast<double>(s.phantoms), static_cast<double>(acceptance.max_phantoms)));
  if (s.long_capture_clips > 0)
    s.failures.push_back(format("clips with a captured run longer than %.0f frames: %.0f (target 0)",
                                static_cast<double>(acceptance.max_captured_run), static_cast<double>(s.long_capture_clips)));
  s.passed = s.failures.empty();
  return s;
}

}  // namespace tachi::sensor
