// Smoothers for the hand trajectory. Seed 000 section 5 proposes a moving average of the hand
// coordinates against Kinect noise; the One Euro filter (Casiez, Roussel, Vogel, CHI 2012) is the
// default because it smooths hard when the hand is slow and follows closely when it is fast.
//
// Tuning the One Euro filter (the paper's procedure, section 3 "Tuning"): set beta = 0 and lower
// min_cutoff_hz until a hand held still stops jittering; then raise beta until a fast stroke no
// longer lags. d_cutoff_hz (cutoff for the speed estimate) rarely needs changing from 1 Hz.
// min_cutoff_hz is in Hz, beta in 1/m (cutoff grows by beta Hz per m/s of hand speed).
#pragma once

#include "tachi/filter/wiener_bank.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tachi::filter {

/// Arithmetic mean of the last N samples (seed 000 section 5). Lags (N - 1) / 2 frames.
class MovingAverage {
 public:
  explicit MovingAverage(std::size_t window);
  Eigen::Vector3f filter(const Eigen::Vector3f& x);
  void reset() { window_.clear(); sum_.setZero(); }
  std::size_t window() const noexcept { return size_; }

 private:
  std::size_t size_;
  std::deque<Eigen::Vector3f> window_;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
};

/// A first-order low-pass x_hat_i = alpha x_i + (1 - alpha) x_hat_{i-1} (eq. (1) of Casiez et al. 2012).
class LowPass {
 public:
  double filter(double x, double alpha);
  void reset() { initialised_ = false; }
  bool initialised() const noexcept { return initialised_; }
  double last() const noexcept { return value_; }

 private:
  bool initialised_ = false;
  double value_ = 0.0;
};

/// Defaults: the paper's filter (no lag compensation), tuned on recordings/jitter by the paper's
/// procedure and a sweep (docs/filter.md, docs/benchmarks.md "Filter and voice"): 2.5 Hz and beta 5
/// halve the tremor error (0.49x raw once the lag is removed) at under 1 frame of lag.
struct OneEuroParams {
  double min_cutoff_hz = 2.5;
  double beta = 5.0;
  double d_cutoff_hz = 1.0;
  /// Lag compensation in [0, 1] (an extension, not in Casiez et al.): adds lag_compensation * tau * v_hat,
  /// where tau = 1 / (2 pi fc) is the low-pass's steady-state lag behind a constant-velocity hand and v_hat
  /// the filtered output's velocity low-passed at the same cutoff. 1 removes the lag on ramps (transfer
  /// (1 + 2 tau s) / (1 + tau s)^2); 0 (the default) is the paper's filter.
  double lag_compensation = 0.0;
};

/// The One Euro filter for one scalar, Algorithm 1 of Casiez, Roussel, Vogel, CHI 2012:
/// alpha = 1 / (1 + tau / Te), tau = 1 / (2 pi fc), fc = fcmin + beta |dx_hat|,
/// dx = (x_i - x_hat_{i-1}) / Te as in the paper's pseudocode (the authors' C++ code does the same since
/// 2023; MediaPipe differentiates the raw signal). Optional lag compensation: see OneEuroParams.
class OneEuroScalar {
 public:
  explicit OneEuroScalar(const OneEuroParams& params) : params_(params) {}
  /// dt_s > 0: time since the previous sample.
  double filter(double x, double dt_s);
  void reset() { x_.reset(); dx_.reset(); v_.reset(); }

 private:
  OneEuroParams params_;
  LowPass x_;
  LowPass dx_;
  LowPass v_;
};

/// Smoothing factor of a first-order low-pass with cutoff `cutoff_hz` sampled every `dt_s` (Casiez et al. eq. (4)).
double one_euro_alpha(double cutoff_hz, double dt_s);

/// The One Euro filter applied per axis (as in the paper) to a 3D position.
class OneEuroFilter {
 public:
  explicit OneEuroFilter(const OneEuroParams& params);
  Eigen::Vector3f filter(const Eigen::Vector3f& x, double dt_s);
  void reset();

 private:
  OneEuroScalar x_, y_, z_;
};

/// A causal FIR whose taps are the Wiener solution for trembling hands: the least-squares
/// filter (Wiener-Hopf normal equations, Wiener 1949; Haykin, Adaptive Filter Theory, ch. 2)
///   x_hat_n = sum_k h_k y_{n-k},  h = argmin sum (x_hat_n - x_{n-d})^2,  sum_k h_k = 1,
/// fitted over the randomized tremor clips of seeds 1-1000 (tremor_clips.hpp; `tachi-filter-bench
/// --fit-wiener 1..1000`) to the intended path d = 0.9 frame earlier. The taps assume the nominal rate:
/// after a dropped frame the history restarts and the One Euro filter bridges it until it is full.
class WienerFir {
 public:
  explicit WienerFir(std::vector<double> taps);
  /// Empty until the history holds as many samples as there are taps.
  std::optional<Eigen::Vector3f> filter(const Eigen::Vector3f& x);
  void reset() { history_.clear(); }

 private:
  std::vector<double> taps_;
  std::deque<Eigen::Vector3d> history_;  ///< newest first
};

/// The taps of `wiener` (12, newest first; they sum to 1).
const std::vector<double>& tremor_wiener_taps();

/// `wiener-bank`: a bank of Wiener FIRs chosen by what the last 12 samples show (wiener_bank.hpp).
enum class SmootherKind { None, MovingAverage, OneEuro, Wiener, WienerBank };

/// "none", "moving-average", "one-euro" (the CLI's spelling) -> kind.
std::optional<SmootherKind> smoother_kind_from_string(const std::string& name);
std::string to_string(SmootherKind kind);

struct SmootherParams {
  /// The Wiener bank: 1.14x the offline ceiling on held-out randomized tremor and 4.93 mm (0.49x raw) on
  /// recordings/jitter, against One Euro's 1.75x and 4.98 mm (docs/filter.md).
  SmootherKind kind = SmootherKind::WienerBank;
  std::size_t moving_average_window = 5;
  OneEuroParams one_euro;
  std::vector<double> wiener_taps = tremor_wiener_taps();
  double nominal_rate_hz = 30.0;   ///< used when timestamps do not advance
  double reset_after_gap_s = 0.5;  ///< a longer gap between tracked samples restarts the filter
};

/// Why parameters are unusable, or nothing when valid.
std::optional<std::string> validate(const SmootherParams& params);

/// Smooths a trajectory of timestamped positions; a lost hand (reset()) or a long gap restarts it.
class Smoother {
 public:
  explicit Smoother(const SmootherParams& params);
  Eigen::Vector3f filter(const Eigen::Vector3f& x, std::int64_t stamp_ns);
  void reset();

 private:
  SmootherParams params_;
  MovingAverage average_;
  OneEuroFilter one_euro_;
  WienerFir wiener_;
  BankedWiener wiener_bank_;
  std::optional<std::int64_t> last_stamp_ns_;
};

}  // namespace tachi::filter
