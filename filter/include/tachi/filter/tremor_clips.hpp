// Randomized trembling-hand clips for tuning and judging the smoother, and the offline
// ceiling a causal smoother is measured against.
//
// A clip is drawn from a seed: a hand path of random shape (sweep, arc, zig-zag, loop) and speed
// (0.03-1.2 m/s, with pauses), tremor of random amplitude (1-8 mm RMS per axis) and frequency
// (physiological 8-12 Hz or essential 4-8 Hz, each a few drifting partials per axis), and sensor
// error shaped like tachi-sensor's on the bundled recordings (white 0.4-1 mm per axis plus a slow
// AR(1) drift of 0.2-1.5 mm: measured against their ground truth, lag-1 autocorrelation 0-0.9), at
// 30 Hz. Tune on seeds 1-1000; report on 100001-100300, which no tuning looks at.
//
// Scores are against the intended path (no tremor), on the frames away from the clip's ends:
// - a causal smoother's lag is the shift of the intended path that minimises its RMS error (0.05-frame
//   steps in [-3, 15] after a 0.25-frame coarse search, linear between frames: as tachi-filter-bench and recording_gate_test measure it),
//   and its error is the RMS at that shift;
// - the ceiling is the best zero-lag offline smoother of the same clip with its width chosen per clip
//   against the ground truth: the better of a centred Gaussian (sigma 0.5-12 frames) and a
//   Savitzky-Golay filter (Savitzky & Golay 1964; orders 2 and 4, half-widths 2-20).
#pragma once

#include "tachi/filter/smoothing.hpp"
#include "tachi/filter/wiener_bank.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace tachi::filter {

struct TremorClip {
  std::uint64_t seed = 0;
  double rate_hz = 30.0;
  std::vector<Eigen::Vector3d> intended;  ///< the hand's path without tremor (ground truth), camera frame
  std::vector<Eigen::Vector3d> measured;  ///< path + tremor + sensor error: what the tracker reports
  std::vector<std::int64_t> stamp_ns;
  // What was drawn, for the tables.
  std::string shape;
  double speed_mps = 0.0;     ///< the path's cruising speed
  double tremor_hz = 0.0;     ///< the tremor's centre frequency
  double tremor_rms_m = 0.0;  ///< per axis
};

/// The clip of one seed (deterministic: the same seed gives the same clip on every machine).
TremorClip make_tremor_clip(std::uint64_t seed);

/// Frames [first, last) of a clip of n frames are scored: 15 frames (0.5 s) are left at each end, where
/// a causal filter is warming up and a centred window runs off the clip.
inline constexpr std::size_t kScoreMargin = 15;

/// RMS distance (m) of `out` at frames [first, last) to the intended path shifted by `shift` frames
/// (out[i] against intended(i - shift), linear between frames). Infinity when nothing could be scored.
double rms_against_shifted(const TremorClip& clip, const std::vector<Eigen::Vector3d>& out, double shift);

struct CausalScore {
  double rms_m = 0.0;       ///< at the lag
  double lag_frames = 0.0;  ///< the error-minimising shift
  double rms_same_frame_m = 0.0;
};
CausalScore score_causal(const TremorClip& clip, const std::vector<Eigen::Vector3d>& out);

/// Zero-phase offline smoothers (centred windows, renormalised where they run off the clip).
std::vector<Eigen::Vector3d> gaussian_smooth(const std::vector<Eigen::Vector3d>& x, double sigma_frames);
std::vector<Eigen::Vector3d> savitzky_golay_smooth(const std::vector<Eigen::Vector3d>& x, int half_width, int order);

struct Ceiling {
  double rms_m = 0.0;
  std::string smoother;  ///< e.g. "gaussian sigma 2.5" or "savitzky-golay order 2 half-width 6"
};
/// The best zero-lag offline smoother of this clip, its width chosen against the ground truth.
Ceiling offline_ceiling(const TremorClip& clip);

/// How fit_wiener_bank fits. The defaults are the shipped bank's (wiener_bank_table.cpp), chosen on the
/// validation seeds 1001-1300 (docs/filter.md).
struct WienerBankFit {
  std::size_t bins = 5;  ///< centres per feature
  double delay = 0.95;   ///< frames: the intended path's delay the taps aim at
  /// How the clips' frames count. What is reported is the mean over clips of (clip RMS / clip's ceiling RMS);
  /// the squared error pooled over every frame (Pooled) lets the clips of large tremor dominate. Ceiling
  /// weighs each clip's frames by 1 / (frames * ceiling^2): the mean over clips of (RMS / ceiling)^2. MeanRatio
  /// starts there, then takes `reweighting_rounds` rounds with 1 / (frames * RMS * ceiling), the RMS the
  /// previous round's bank makes of the clip at `delay`: iteratively reweighted least squares (the gradient of
  /// sum RMS / ceiling is that of sum RMS^2 / (2 RMS ceiling)) toward the mean of RMS / ceiling itself.
  enum class Weighting { Pooled, Ceiling, MeanRatio };
  Weighting weighting = Weighting::MeanRatio;
  int reweighting_rounds = 2;
  /// Of the mean diagonal: pulls each bin toward the one FIR fitted with the same weights over all the frames.
  double ridge = 1e-4;
};

/// Fits a WienerBank (wiener_bank.hpp) over `clips`: `bins` centres per feature at the quantiles
/// (b + 1/2) / bins of the features over every full history, then every bin's gains at once by weighted least
/// squares (each clip's frames weighted as fit.weighting says) against the intended path `delay` frames
/// earlier, through the trilinear interpolation the filter uses, on the scored frames (kScoreMargin from each
/// end); a light ridge pulls bins the clips hardly visit toward the one FIR fitted over all of them.
WienerBank fit_wiener_bank(const std::vector<TremorClip>& clips, const WienerBankFit& fit);

/// Runs a tachi smoother over the clip's measured samples, as the filter stage would.
std::vector<Eigen::Vector3d> run_smoother(const TremorClip& clip, const SmootherParams& params);

}  // namespace tachi::filter
