// A bank of causal Wiener FIRs scheduled by what the filter's own history shows (gain scheduling).
//
// One 12-tap Wiener FIR fitted over every randomized trembling hand (smoothing.hpp, `wiener`) is the best
// time-invariant filter for the whole distribution, 1.46-1.50x the offline ceiling. A hand's best filter
// depends on its tremor's frequency and size and on its speed: each clip's own least-squares FIR (an
// oracle that knows the clip's truth) reaches 1.08x, and a bank chosen by the clip's drawn tremor
// frequency alone 1.23x (`tachi-filter-bench --oracle-fir`, docs/filter.md). The bank here is chosen from
// the last 12 samples, which the FIR holds anyway: how rough the motion is (RMS second difference over
// RMS first difference, 2 sin(w/2) for a sinusoid of w rad/frame), how large that roughness is, and the
// mean speed. The taps are interpolated (trilinearly) between the bins' centres, so the output is
// continuous in the input; the bins' taps are fitted jointly through that interpolation, by least squares
// against the intended path 0.95 frame earlier (Wiener 1949; Haykin, Adaptive Filter Theory, ch. 2; gain
// scheduling as in Rugh & Shamma 2000, "Research on gain scheduling"). The squares are weighted per clip
// toward the figure the smoother is judged by, the mean over clips of (RMS / the clip's offline ceiling):
// a pooled fit let the clips of large tremor, whose errors are largest, set the taps for every hand
// (fit_wiener_bank, tremor_clips.hpp).
#pragma once

#include <Eigen/Core>

#include <array>
#include <deque>
#include <optional>
#include <vector>

namespace tachi::filter {

struct WienerBank {
  static constexpr std::size_t kTaps = 12;
  static constexpr std::size_t kFeatures = 3;
  /// Per feature, the bins' centres, ascending (at least two each).
  std::array<std::vector<double>, kFeatures> centres;
  /// Per bin (the first feature's index slowest), g_1..g_11 of out = y_0 + sum_k g_k (y_k - y_0), y_0 the
  /// newest sample: translation invariant (the taps sum to 1 whatever g is).
  std::vector<std::array<double, kTaps - 1>> gains;
  [[nodiscard]] std::size_t bins() const { return centres[0].size() * centres[1].size() * centres[2].size(); }
};

/// The three features of a full history (newest first, WienerBank::kTaps samples): roughness, log RMS
/// second difference (m), log mean speed (m per frame).
std::array<double, WienerBank::kFeatures> history_features(const std::deque<Eigen::Vector3d>& newest_first);

/// Up to eight bins and their weights (summing to 1) for the features: trilinear between the centres,
/// clamped at the outer ones. Non-finite features take the first centre.
struct BinWeights {
  std::array<std::size_t, 8> bin{};
  std::array<double, 8> weight{};
};
BinWeights bin_weights(const WienerBank& bank, const std::array<double, WienerBank::kFeatures>& features);

/// The bank fitted over the randomized tremor clips of seeds 1-1000 with WienerBankFit's defaults
/// (`tachi-filter-bench --fit-wiener-bank 1..1000` prints it; a test checks that it still does).
const WienerBank& tremor_wiener_bank();

/// The scheduled FIR over a stream of samples at the nominal rate (as WienerFir: a dropped frame restarts
/// the history, and it is empty until the history is full).
class BankedWiener {
 public:
  explicit BankedWiener(const WienerBank& bank) : bank_(&bank) {}
  std::optional<Eigen::Vector3f> filter(const Eigen::Vector3f& x);
  void reset() { history_.clear(); }

 private:
  const WienerBank* bank_;
  std::deque<Eigen::Vector3d> history_;  ///< newest first
};

}  // namespace tachi::filter
