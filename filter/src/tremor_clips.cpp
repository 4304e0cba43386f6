#include "tachi/filter/tremor_clips.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace tachi::filter {
namespace {

constexpr double kPi = std::numbers::pi;

/// Catmull-Rom through the control points, sampled densely: a smooth path whose corners round off.
std::vector<Eigen::Vector3d> catmull_rom(const std::vector<Eigen::Vector3d>& p, int per_segment) {
  std::vector<Eigen::Vector3d> out;
  const auto at = [&](int i) { return p[static_cast<std::size_t>(std::clamp(i, 0, static_cast<int>(p.size()) - 1))]; };
  for (int s = 0; s + 1 < static_cast<int>(p.size()); ++s) {
    const Eigen::Vector3d p0 = at(s - 1), p1 = at(s), p2 = at(s + 1), p3 = at(s + 2);
    for (int k = 0; k < per_segment; ++k) {
      const double t = static_cast<double>(k) / per_segment, t2 = t * t, t3 = t2 * t;
      out.push_back(0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2 + (-p0 + 3 * p1 - 3 * p2 + p3) * t3));
    }
  }
  out.push_back(p.back());
  return out;
}

/// The point at arc length s along a polyline with cumulative lengths `cum`.
Eigen::Vector3d along(const std::vector<Eigen::Vector3d>& line, const std::vector<double>& cum, double s) {
  if (s <= 0) return line.front();
  if (s >= cum.back()) return line.back();
  const auto it = std::upper_bound(cum.begin(), cum.end(), s);
  const auto i = static_cast<std::size_t>(it - cum.begin());
  const double w = (s - cum[i - 1]) / std::max(cum[i] - cum[i - 1], 1e-12);
  return (1 - w) * line[i - 1] + w * line[i];
}

}  // namespace

TremorClip make_tremor_clip(std::uint64_t seed) {
  std::mt19937_64 rng{seed * 0x9E3779B97F4A7C15ULL + 0x7A3C11ULL};
  const auto uni = [&](double lo, double hi) { return std::uniform_real_distribution<double>{lo, hi}(rng); };
  const auto log_uni = [&](double lo, double hi) { return std::exp(uni(std::log(lo), std::log(hi))); };
  std::normal_distribution<double> gauss{0.0, 1.0};

  TremorClip clip;
  clip.seed = seed;
  const double fps = clip.rate_hz;
  const auto frames = static_cast<std::size_t>(std::lround(uni(4.0, 6.0) * fps));

  // The path: control points in the camera frame (x right, y down, z forward) within reach of a
  // user 0.8-1.4 m from the sensor; mostly across the image, a little in depth.
  const Eigen::Vector3d start{uni(-0.3, 0.3), uni(-0.2, 0.2), uni(0.8, 1.4)};
  const double extent = uni(0.1, 0.6);
  std::vector<Eigen::Vector3d> control{start};
  const int shape = std::uniform_int_distribution<int>{0, 3}(rng);
  const double heading = uni(0, 2 * kPi);
  const Eigen::Vector3d dir{std::cos(heading), std::sin(heading), uni(-0.2, 0.2)};
  const Eigen::Vector3d side = Eigen::Vector3d{-dir.y(), dir.x(), 0.0}.normalized();
  switch (shape) {
    case 0:  // a sweep
      clip.shape = "sweep";
      control.push_back(start + extent * dir.normalized());
      break;
    case 1: {  // an arc
      clip.shape = "arc";
      const double bend = uni(-0.5, 0.5) * extent;
      for (int k = 1; k <= 4; ++k) {
        const double s = k / 4.0;
        control.push_back(start + extent * s * dir.normalized() + bend * std::sin(kPi * s) * side);
      }
      break;
    }
    case 2: {  // a zig-zag
      clip.shape = "zig-zag";
      const int legs = std::uniform_int_distribution<int>{3, 6}(rng);
      const double width = uni(0.05, 0.2);
      for (int k = 1; k <= legs; ++k)
        control.push_back(start + extent * (static_cast<double>(k) / legs) * dir.normalized() + ((k % 2) ? width : -width) * side);
      break;
    }
    default: {  // a loop
      clip.shape = "loop";
      const double r = extent / 2;
      for (int k = 1; k <= 8; ++k) {
        const double a = 2 * kPi * k / 8;
        control.push_back(start + r * (std::sin(a) * dir.normalized() + (1 - std::cos(a)) * side));
      }
      break;
    }
  }
  const auto line = catmull_rom(control, 64);
  std::vector<double> cum{0.0};
  for (std::size_t i = 1; i < line.size(); ++i) cum.push_back(cum.back() + (line[i] - line[i - 1]).norm());

  // Speed: a cruising speed with a slow wobble, eased in and out, and sometimes a pause mid-path.
  clip.speed_mps = log_uni(0.03, 1.2);
  const double wobble = uni(0.0, 0.4), wobble_hz = uni(0.2, 1.0), wobble_phase = uni(0, 2 * kPi);
  const bool pause = uni(0, 1) < 0.3;
  const double pause_at = uni(0.3, 0.6) * static_cast<double>(frames) / fps, pause_s = uni(0.3, 1.0);
  std::vector<double> s_of_frame(frames, 0.0);
  const double start_s = uni(0.0, 0.3), dt = 1.0 / fps;
  double s = 0.0;
  for (std::size_t i = 0; i < frames; ++i) {
    const double t = static_cast<double>(i) * dt;
    // Integrated at 10 sub-steps a frame so the path is smooth between frames.
    for (int k = 0; k < 10; ++k) {
      const double tt = t + k * dt / 10;
      double v = clip.speed_mps * (1 + wobble * std::sin(2 * kPi * wobble_hz * tt + wobble_phase));
      v *= 0.5 - 0.5 * std::cos(kPi * std::clamp((tt - start_s) / 0.4, 0.0, 1.0));  // ease in
      if (pause) {
        const double d = std::abs(tt - (pause_at + pause_s / 2)) - pause_s / 2;  // < 0 inside the pause
        v *= 0.5 - 0.5 * std::cos(kPi * std::clamp(d / 0.25, 0.0, 1.0));
      }
      s += v * dt / 10;
    }
    s_of_frame[i] = s;
  }
  // A path shorter than the motion: the hand stops at its end (it does not run off).
  clip.intended.resize(frames);
  for (std::size_t i = 0; i < frames; ++i) clip.intended[i] = along(line, cum, s_of_frame[i]);

  // Tremor: physiological (8-12 Hz) or essential (4-8 Hz); per axis 2-3 partials around the centre
  // frequency, each drifting slowly in frequency and amplitude, scaled to the drawn RMS with random
  // weights per axis (tremor has a dominant direction).
  const bool physiological = uni(0, 1) < 0.5;
  clip.tremor_hz = physiological ? uni(8.0, 12.0) : uni(4.0, 8.0);
  clip.tremor_rms_m = log_uni(0.001, 0.008);
  Eigen::Vector3d weight{uni(0.3, 1.0), uni(0.3, 1.0), uni(0.3, 1.0)};
  weight *= std::sqrt(3.0) / weight.norm();
  struct Partial {
    double hz, phase, drift_hz, drift_phase, amp_phase;
  };
  std::array<std::vector<Partial>, 3> partials;
  for (auto& axis : partials) {
    const int n = std::uniform_int_distribution<int>{2, 3}(rng);
    for (int k = 0; k < n; ++k)
      axis.push_back({std::clamp(clip.tremor_hz + uni(-0.7, 0.7), 3.5, 13.0), uni(0, 2 * kPi), uni(0.1, 0.4), uni(0, 2 * kPi), uni(0, 2 * kPi)});
  }
  // Sensor error like tachi-sensor's (see the header): white plus a slow AR(1) drift, per axis.
  Eigen::Vector3d white_sd, drift_sd, rho;
  for (int a = 0; a < 3; ++a) {
    white_sd[a] = uni(0.0004, 0.001);
    drift_sd[a] = uni(0.0002, 0.0015);
    rho[a] = uni(0.85, 0.95);
  }
  Eigen::Vector3d drift;
  for (int a = 0; a < 3; ++a) drift[a] = drift_sd[a] * gauss(rng);

  clip.measured.resize(frames);
  clip.stamp_ns.resize(frames);
  for (std::size_t i = 0; i < frames; ++i) {
    const double t = static_cast<double>(i) * dt;
    Eigen::Vector3d tremor = Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      const auto& axis = partials[static_cast<std::size_t>(a)];
      double v = 0.0;
      for (const auto& p : axis) {
        // Phase of a partial whose frequency wobbles by +-0.3 Hz: integral of 2 pi f(t).
        const double phase = 2 * kPi * p.hz * t + 0.3 / p.drift_hz * std::sin(2 * kPi * p.drift_hz * t + p.drift_phase) + p.phase;
        v += (1 + 0.3 * std::sin(2 * kPi * 0.3 * t + p.amp_phase)) * std::sin(phase);
      }
      // Each partial has RMS ~ sqrt((1 + 0.045) / 2); scale the sum to the drawn RMS.
      tremor[a] = clip.tremor_rms_m * weight[a] * v / std::sqrt(static_cast<double>(axis.size()) * 1.045 / 2);
    }
    for (int a = 0; a < 3; ++a) {
      drift[a] = rho[a] * drift[a] + std::sqrt(1 - rho[a] * rho[a]) * drift_sd[a] * gauss(rng);
      tremor[a] += drift[a] + white_sd[a] * gauss(rng);
    }
    clip.measured[i] = clip.intended[i] + tremor;
    clip.stamp_ns[i] = 1'000'000'000LL + static_cast<std::int64_t>(std::llround(t * 1e9));
  }
  return clip;
}

double rms_against_shifted(const TremorClip& clip, const std::vector<Eigen::Vector3d>& out, double shift) {
  const std::size_t n = std::min(out.size(), clip.intended.size());
  if (n <= 2 * kScoreMargin) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = kScoreMargin; i < n - kScoreMargin; ++i) {
    const double t = static_cast<double>(i) - shift;
    const double f = std::floor(t);
    if (f < 0 || f + 1 >= static_cast<double>(clip.intended.size())) continue;
    const auto k = static_cast<std::size_t>(f);
    const double w = t - f;
    sum += (out[i] - ((1 - w) * clip.intended[k] + w * clip.intended[k + 1])).squaredNorm();
    ++count;
  }
  return count == 0 ? std::numeric_limits<double>::infinity() : std::sqrt(sum / static_cast<double>(count));
}

CausalScore score_causal(const TremorClip& clip, const std::vector<Eigen::Vector3d>& out) {
  CausalScore best;
  best.rms_m = std::numeric_limits<double>::infinity();
  best.rms_same_frame_m = rms_against_shifted(clip, out, 0.0);
  // Coarse (0.25 frame) then fine (0.05 frame) around the coarse minimum: the error is smooth in the shift.
  const auto try_shift = [&](double shift) {
    const double r = rms_against_shifted(clip, out, shift);
    if (r < best.rms_m) best = {r, shift, best.rms_same_frame_m};
  };
  for (int k = -12; k <= 60; ++k) try_shift(0.25 * k);
  const double coarse = best.lag_frames;
  for (int k = -4; k <= 4; ++k) try_shift(coarse + 0.05 * k);
  return best;
}

std::vector<Eigen::Vector3d> gaussian_smooth(const std::vector<Eigen::Vector3d>& x, double sigma_frames) {
  const int n = static_cast<int>(x.size());
  const int half = static_cast<int>(std::ceil(4 * sigma_frames));
  std::vector<double> w(static_cast<std::size_t>(half) + 1);
  for (int k = 0; k <= half; ++k) w[static_cast<std::size_t>(k)] = std::exp(-0.5 * k * k / (sigma_frames * sigma_frames));
  std::vector<Eigen::Vector3d> out(x.size());
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double total = 0.0;
    for (int j = std::max(0, i - half); j <= std::min(n - 1, i + half); ++j) {
      const double wj = w[static_cast<std::size_t>(std::abs(j - i))];
      sum += wj * x[static_cast<std::size_t>(j)];
      total += wj;
    }
    out[static_cast<std::size_t>(i)] = sum / total;
  }
  return out;
}

std::vector<Eigen::Vector3d> savitzky_golay_smooth(const std::vector<Eigen::Vector3d>& x, int half_width, int order) {
  const int n = static_cast<int>(x.size());
  std::vector<Eigen::Vector3d> out(x.size());
  // The least-squares polynomial over the window [lo, hi] evaluated at i: the first row of the
  // pseudo-inverse of the Vandermonde matrix in (j - i). Interior points share one set of weights.
  const auto weights = [&](int lo, int hi, int i) {
    const int m = hi - lo + 1;
    const int p = std::min(order, m - 1);
    Eigen::MatrixXd a(m, p + 1);
    for (int r = 0; r < m; ++r)
      for (int c = 0; c <= p; ++c) a(r, c) = std::pow(static_cast<double>(lo + r - i), c);
    const Eigen::MatrixXd pinv = (a.transpose() * a).ldlt().solve(a.transpose());
    return Eigen::VectorXd{pinv.row(0).transpose()};
  };
  const Eigen::VectorXd interior = weights(-half_width, half_width, 0);
  for (int i = 0; i < n; ++i) {
    const int lo = std::max(0, i - half_width), hi = std::min(n - 1, i + half_width);
    const Eigen::VectorXd w = (lo == i - half_width && hi == i + half_width) ? interior : weights(lo, hi, i);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j = lo; j <= hi; ++j) sum += w[j - lo] * x[static_cast<std::size_t>(j)];
    out[static_cast<std::size_t>(i)] = sum;
  }
  return out;
}

Ceiling offline_ceiling(const TremorClip& clip) {
  Ceiling best{std::numeric_limits<double>::infinity(), ""};
  char name[96];
  for (double sigma = 0.5; sigma <= 12.0; sigma += (sigma < 4 ? 0.25 : 0.5)) {
    const double r = rms_against_shifted(clip, gaussian_smooth(clip.measured, sigma), 0.0);
    if (r < best.rms_m) {
      std::snprintf(name, sizeof name, "gaussian sigma %.2f", sigma);
      best = {r, name};
    }
  }
  for (int order : {2, 4}) {
    for (int half = order / 2 + 1; half <= 20; ++half) {
      const double r = rms_against_shifted(clip, savitzky_golay_smooth(clip.measured, half, order), 0.0);
      if (r < best.rms_m) {
        std::snprintf(name, sizeof name, "savitzky-golay order %d half-width %d", order, half);
        best = {r, name};
      }
    }
  }
  return best;
}

std::vector<Eigen::Vector3d> run_smoother(const TremorClip& clip, const SmootherParams& params) {
  Smoother smoother{params};
  std::vector<Eigen::Vector3d> out;
  out.reserve(clip.measured.size());
  for (std::size_t i = 0; i < clip.measured.size(); ++i)
    out.push_back(smoother.filter(clip.measured[i].cast<float>(), clip.stamp_ns[i]).cast<double>());
  return out;
}

}  // namespace tachi::filter
