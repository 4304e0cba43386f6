#include "tachi/filter/smoothing.hpp"

#include "fir_history.hpp"

#include <cmath>
#include <numbers>

namespace tachi::filter {

MovingAverage::MovingAverage(std::size_t window) : size_(window == 0 ? 1 : window) {}

Eigen::Vector3f MovingAverage::filter(const Eigen::Vector3f& x) {
  window_.push_back(x);
  sum_ += x.cast<double>();
  if (window_.size() > size_) {
    sum_ -= window_.front().cast<double>();
    window_.pop_front();
  }
  return (sum_ / static_cast<double>(window_.size())).cast<float>();
}

double LowPass::filter(double x, double alpha) {
  value_ = initialised_ ? alpha * x + (1.0 - alpha) * value_ : x;
  initialised_ = true;
  return value_;
}

double one_euro_alpha(double cutoff_hz, double dt_s) {
  const double tau = 1.0 / (2.0 * std::numbers::pi * cutoff_hz);
  return 1.0 / (1.0 + tau / dt_s);
}

double OneEuroScalar::filter(double x, double dt_s) {
  // The first sample passes through with a zero speed estimate (the paper's initialisation).
  const double dx = x_.initialised() ? (x - x_.last()) / dt_s : 0.0;
  const double edx = dx_.filter(dx, one_euro_alpha(params_.d_cutoff_hz, dt_s));
  const double cutoff = params_.min_cutoff_hz + params_.beta * std::abs(edx);
  const bool first = !x_.initialised();
  const double previous = x_.last();
  const double alpha = one_euro_alpha(cutoff, dt_s);
  const double x_hat = x_.filter(x, alpha);
  if (params_.lag_compensation <= 0.0) return x_hat;
  // A first-order low-pass trails a constant velocity v by v * tau; add back the estimate of that lag.
  const double v_hat = v_.filter(first ? 0.0 : (x_hat - previous) / dt_s, alpha);
  return x_hat + params_.lag_compensation * v_hat / (2.0 * std::numbers::pi * cutoff);
}

OneEuroFilter::OneEuroFilter(const OneEuroParams& params) : x_(params), y_(params), z_(params) {}

Eigen::Vector3f OneEuroFilter::filter(const Eigen::Vector3f& x, double dt_s) {
  return {static_cast<float>(x_.filter(x.x(), dt_s)), static_cast<float>(y_.filter(x.y(), dt_s)),
          static_cast<float>(z_.filter(x.z(), dt_s))};
}

void OneEuroFilter::reset() {
  x_.reset();
  y_.reset();
  z_.reset();
}

WienerFir::WienerFir(std::vector<double> taps) : taps_(std::move(taps)) {}

std::optional<Eigen::Vector3f> WienerFir::filter(const Eigen::Vector3f& x) {
  if (!push_history(history_, x, taps_.size())) return std::nullopt;
  return relative_fir(history_, std::span<const double>(taps_).subspan(1));
}

const std::vector<double>& tremor_wiener_taps() {
  // tachi-filter-bench --fit-wiener 1..1000 (12 taps, delay 0.9 frame); docs/filter.md.
  static const std::vector<double> taps{0.387865, 0.186547, 0.377026, 0.026899, 0.179829, -0.114524,
                                        0.036208, -0.107109, 0.005589, -0.018385, 0.021749, 0.018308};
  return taps;
}

std::optional<SmootherKind> smoother_kind_from_string(const std::string& name) {
  if (name == "none") return SmootherKind::None;
  if (name == "moving-average") return SmootherKind::MovingAverage;
  if (name == "one-euro") return SmootherKind::OneEuro;
  if (name == "wiener") return SmootherKind::Wiener;
  if (name == "wiener-bank") return SmootherKind::WienerBank;
  return std::nullopt;
}

std::string to_string(SmootherKind kind) {
  switch (kind) {
    case SmootherKind::None: return "none";
    case SmootherKind::MovingAverage: return "moving-average";
    case SmootherKind::OneEuro: return "one-euro";
    case SmootherKind::Wiener: return "wiener";
    case SmootherKind::WienerBank: return "wiener-bank";
  }
  return "?";
}

std::optional<std::string> validate(const SmootherParams& p) {
  if (p.moving_average_window < 1 || p.moving_average_window > 1000) return "moving_average_window must be in [1, 1000]";
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(p.one_euro.min_cutoff_hz) || p.one_euro.min_cutoff_hz > 1000.0)
    return "min_cutoff_hz must be in (0, 1000]";
  if (!std::isfinite(p.one_euro.beta) || p.one_euro.beta < 0.0 || p.one_euro.beta > 1e6)
    return "beta must be in [0, 1e6]";
  if (!positive(p.one_euro.d_cutoff_hz) || p.one_euro.d_cutoff_hz > 1000.0) return "d_cutoff_hz must be in (0, 1000]";
  if (!std::isfinite(p.one_euro.lag_compensation) || p.one_euro.lag_compensation < 0.0 || p.one_euro.lag_compensation > 1.0)
    return "lag_compensation must be in [0, 1]";
  if (!positive(p.nominal_rate_hz) || p.nominal_rate_hz > 10000.0) return "nominal_rate_hz must be in (0, 10000]";
  if (!positive(p.reset_after_gap_s)) return "reset_after_gap_s must be > 0";
  return std::nullopt;
}

Smoother::Smoother(const SmootherParams& params)
    : params_(params), average_(params.moving_average_window), one_euro_(params.one_euro), wiener_(params.wiener_taps),
      wiener_bank_(tremor_wiener_bank()) {}

void Smoother::reset() {
  average_.reset();
  one_euro_.reset();
  wiener_.reset();
  wiener_bank_.reset();
  last_stamp_ns_.reset();
}

Eigen::Vector3f Smoother::filter(const Eigen::Vector3f& x, std::int64_t stamp_ns) {
  double dt_s = 1.0 / params_.nominal_rate_hz;
  if (last_stamp_ns_) {
    const double gap = static_cast<double>(stamp_ns - *last_stamp_ns_) * 1e-9;
    if (gap > params_.reset_after_gap_s) {
      reset();
    } else if (gap > 0.0) {
      dt_s = gap;  // timestamps that do not advance fall back to the nominal rate
    }
  }
  // The Wiener taps hold for samples at the nominal rate: a dropped frame (or a burst) restarts them.
  if (last_stamp_ns_ && std::abs(dt_s * params_.nominal_rate_hz - 1.0) > 0.5) {
    wiener_.reset();
    wiener_bank_.reset();
  }
  last_stamp_ns_ = stamp_ns;
  switch (params_.kind) {
    case SmootherKind::None: return x;
    case SmootherKind::MovingAverage: return average_.filter(x);
    case SmootherKind::OneEuro: return one_euro_.filter(x, dt_s);
    case SmootherKind::Wiener: {
      // The One Euro filter runs alongside and bridges the Wiener filter's warm-up.
      const Eigen::Vector3f bridge = one_euro_.filter(x, dt_s);
      return wiener_.filter(x).value_or(bridge);
    }
    case SmootherKind::WienerBank: {
      const Eigen::Vector3f bridge = one_euro_.filter(x, dt_s);
      return wiener_bank_.filter(x).value_or(bridge);
    }
  }
  return x;
}

}  // namespace tachi::filter
