// The scheduled Wiener FIR (wiener_bank.hpp): its features, the interpolation between its bins, the filter,
// and the fit over the randomized tremor clips (tremor_clips.hpp).
#include "tachi/filter/wiener_bank.hpp"

#include "tachi/filter/tremor_clips.hpp"

#include "fir_history.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace tachi::filter {

namespace {

constexpr std::size_t kGains = WienerBank::kTaps - 1;

/// The features of the history ending at frame n of a clip (oldest first), as history_features.
std::array<double, WienerBank::kFeatures> features_at(const std::vector<Eigen::Vector3d>& y, std::size_t n) {
  std::deque<Eigen::Vector3d> h;
  for (std::size_t k = 0; k < WienerBank::kTaps; ++k) h.push_back(y[n - k]);
  return history_features(h);
}

/// Position of x among ascending centres, in centre units: 0 at the first, size - 1 at the last (clamped).
double position(const std::vector<double>& centres, double x) {
  if (!std::isfinite(x) || x <= centres.front()) return 0.0;
  if (x >= centres.back()) return static_cast<double>(centres.size() - 1);
  const auto upper = static_cast<std::size_t>(std::upper_bound(centres.begin(), centres.end(), x) - centres.begin());
  const double lo = centres[upper - 1], hi = centres[upper];
  return static_cast<double>(upper - 1) + (x - lo) / (hi - lo);
}

}  // namespace

std::array<double, WienerBank::kFeatures> history_features(const std::deque<Eigen::Vector3d>& y) {
  double first = 0.0, second = 0.0;
  for (std::size_t k = 0; k + 1 < WienerBank::kTaps; ++k) first += (y[k] - y[k + 1]).squaredNorm();
  for (std::size_t k = 0; k + 2 < WienerBank::kTaps; ++k) second += (y[k] - 2.0 * y[k + 1] + y[k + 2]).squaredNorm();
  const double rms_first = std::sqrt(first / static_cast<double>(WienerBank::kTaps - 1));
  const double rms_second = std::sqrt(second / static_cast<double>(WienerBank::kTaps - 2));
  const double speed = (y[0] - y[WienerBank::kTaps - 1]).norm() / static_cast<double>(WienerBank::kTaps - 1);
  // Floors far below the sensor's noise keep a still hand's features finite.
  return {rms_second / std::max(rms_first, 1e-9), std::log(std::max(rms_second, 1e-7)), std::log(std::max(speed, 1e-7))};
}

BinWeights bin_weights(const WienerBank& bank, const std::array<double, WienerBank::kFeatures>& features) {
  std::array<std::size_t, WienerBank::kFeatures> low{};
  std::array<double, WienerBank::kFeatures> t{};
  for (std::size_t d = 0; d < WienerBank::kFeatures; ++d) {
    const double p = position(bank.centres[d], features[d]);
    low[d] = std::min(static_cast<std::size_t>(p), bank.centres[d].size() - 2);
    t[d] = p - static_cast<double>(low[d]);
  }
  BinWeights out;
  for (std::size_t corner = 0; corner < 8; ++corner) {
    std::size_t bin = 0;
    double weight = 1.0;
    for (std::size_t d = 0; d < WienerBank::kFeatures; ++d) {
      const bool up = ((corner >> d) & 1U) != 0;
      bin = bin * bank.centres[d].size() + low[d] + (up ? 1 : 0);
      weight *= up ? t[d] : 1.0 - t[d];
    }
    out.bin[corner] = bin;
    out.weight[corner] = weight;
  }
  return out;
}

std::optional<Eigen::Vector3f> BankedWiener::filter(const Eigen::Vector3f& x) {
  if (!push_history(history_, x, WienerBank::kTaps)) return std::nullopt;
  const BinWeights w = bin_weights(*bank_, history_features(history_));
  std::array<double, kGains> gains{};
  for (std::size_t c = 0; c < 8; ++c) {
    for (std::size_t k = 0; k < kGains; ++k) gains[k] += w.weight[c] * bank_->gains[w.bin[c]][k];
  }
  return relative_fir(history_, gains);
}

namespace {

/// What one scored frame of a clip gives the fit: per axis the row y_k - y_0 (k = 1..11, newest first) and the
/// target, the intended path `delay` frames earlier relative to y_0; and the bins' weights of its history.
struct FitFrame {
  std::array<Eigen::Matrix<double, kGains, 1>, 3> row;
  Eigen::Vector3d target;
  BinWeights bins;
};

/// The first frame the fit scores (kScoreMargin from the clip's start, with a full history), and the number it scores.
constexpr std::size_t kFirstFitFrame = std::max(kScoreMargin, WienerBank::kTaps);
std::size_t fit_frames(const TremorClip& c) {
  return c.measured.size() > kFirstFitFrame + kScoreMargin ? c.measured.size() - kFirstFitFrame - kScoreMargin : 0;
}

/// Calls visit(FitFrame) for every scored frame of the clip.
template <typename Visit>
void for_each_fit_frame(const WienerBank& bank, const TremorClip& c, double delay, Visit&& visit) {
  FitFrame f;
  for (std::size_t i = kFirstFitFrame; i + kScoreMargin < c.measured.size(); ++i) {
    const double t = static_cast<double>(i) - delay;
    const auto before = static_cast<std::size_t>(std::floor(t));
    const double w = t - static_cast<double>(before);
    f.target = (1 - w) * c.intended[before] + w * c.intended[before + 1] - c.measured[i];
    for (int a = 0; a < 3; ++a) {
      for (std::size_t k = 1; k <= kGains; ++k) f.row[a][static_cast<Eigen::Index>(k - 1)] = c.measured[i - k][a] - c.measured[i][a];
    }
    f.bins = bin_weights(bank, features_at(c.measured, i));
    visit(f);
  }
}

/// Every bin's gains at once by weighted least squares through the interpolation (a frame's prediction is
/// sum_c w_c (g_c . row) per axis; clip_weight[j] weighs every frame of clip j), with a ridge of `ridge` times
/// the mean diagonal pulling each bin toward the one FIR fitted with the same weights over all the frames.
std::vector<std::array<double, kGains>> solve_gains(const WienerBank& bank, const std::vector<TremorClip>& clips,
                                                    double delay, const std::vector<double>& clip_weight, double ridge) {
  const auto unknowns = static_cast<Eigen::Index>(bank.bins() * kGains);
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(unknowns, unknowns);
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(unknowns);
  Eigen::Matrix<double, kGains, kGains> all_ata = Eigen::Matrix<double, kGains, kGains>::Zero();
  Eigen::Matrix<double, kGains, 1> all_atb = Eigen::Matrix<double, kGains, 1>::Zero();
  for (std::size_t j = 0; j < clips.size(); ++j) {
    for_each_fit_frame(bank, clips[j], delay, [&](const FitFrame& f) {
      Eigen::Matrix<double, kGains, kGains> rr = Eigen::Matrix<double, kGains, kGains>::Zero();
      Eigen::Matrix<double, kGains, 1> rt = Eigen::Matrix<double, kGains, 1>::Zero();
      for (int a = 0; a < 3; ++a) {
        rr += clip_weight[j] * f.row[a] * f.row[a].transpose();
        rt += clip_weight[j] * f.row[a] * f.target[a];
      }
      all_ata += rr;
      all_atb += rt;
      for (std::size_t p = 0; p < 8; ++p) {
        if (f.bins.weight[p] == 0.0) continue;
        const auto at_p = static_cast<Eigen::Index>(f.bins.bin[p] * kGains);
        atb.segment<kGains>(at_p) += f.bins.weight[p] * rt;
        for (std::size_t q = 0; q < 8; ++q) {
          if (f.bins.weight[q] == 0.0) continue;
          const auto at_q = static_cast<Eigen::Index>(f.bins.bin[q] * kGains);
          ata.block<kGains, kGains>(at_p, at_q) += f.bins.weight[p] * f.bins.weight[q] * rr;
        }
      }
    });
  }
  const Eigen::Matrix<double, kGains, 1> global = all_ata.ldlt().solve(all_atb);
  const double lambda = ridge * ata.diagonal().mean();
  for (std::size_t b = 0; b < bank.bins(); ++b) {
    const auto at = static_cast<Eigen::Index>(b * kGains);
    ata.block<kGains, kGains>(at, at) += lambda * Eigen::Matrix<double, kGains, kGains>::Identity();
    atb.segment<kGains>(at) += lambda * global;
  }
  const Eigen::VectorXd g = ata.ldlt().solve(atb);
  std::vector<std::array<double, kGains>> gains(bank.bins());
  for (std::size_t b = 0; b < bank.bins(); ++b) {
    for (std::size_t k = 0; k < kGains; ++k) gains[b][k] = g[static_cast<Eigen::Index>(b * kGains + k)];
  }
  return gains;
}

/// The bank's RMS error on the clip's scored frames against the intended path `delay` frames earlier (what
/// the fit aims at; the bench scores at the error-minimising lag instead).
double fit_rms(const WienerBank& bank, const TremorClip& clip, double delay) {
  double sum = 0.0;
  std::size_t n = 0;
  for_each_fit_frame(bank, clip, delay, [&](const FitFrame& f) {
    Eigen::Matrix<double, kGains, 1> g = Eigen::Matrix<double, kGains, 1>::Zero();
    for (std::size_t c = 0; c < 8; ++c) {
      for (std::size_t k = 0; k < kGains; ++k) g[static_cast<Eigen::Index>(k)] += f.bins.weight[c] * bank.gains[f.bins.bin[c]][k];
    }
    for (int a = 0; a < 3; ++a) sum += std::pow(f.target[a] - g.dot(f.row[a]), 2);
    ++n;
  });
  return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

}  // namespace

WienerBank fit_wiener_bank(const std::vector<TremorClip>& clips, const WienerBankFit& fit) {
  WienerBank bank;
  // The centres: quantiles of each feature over every full history of the clips.
  std::array<std::vector<double>, WienerBank::kFeatures> values;
  for (const auto& c : clips) {
    for (std::size_t n = WienerBank::kTaps - 1; n < c.measured.size(); ++n) {
      const auto f = features_at(c.measured, n);
      for (std::size_t d = 0; d < WienerBank::kFeatures; ++d) values[d].push_back(f[d]);
    }
  }
  for (std::size_t d = 0; d < WienerBank::kFeatures; ++d) {
    std::sort(values[d].begin(), values[d].end());
    for (std::size_t b = 0; b < fit.bins; ++b) {
      bank.centres[d].push_back(values[d][std::min(values[d].size() - 1, (2 * b + 1) * values[d].size() / (2 * fit.bins))]);
    }
  }
  // What is minimised. The smoother is judged by the mean over clips of RMS / ceiling (tachi-filter-bench
  // --tremor); the squared error pooled over every frame is dominated by the clips of large tremor, whose
  // errors are largest, so the clips the ratio is hardest on count least. Weighting each clip's squares by
  // 1 / (frames * ceiling^2) fits the mean of (RMS / ceiling)^2; the reweighted rounds move that to the mean
  // of RMS / ceiling (its gradient is that of a weighted sum of squares with 1 / (frames * RMS * ceiling)).
  std::vector<double> ceiling(clips.size(), 1.0), weight(clips.size(), 1.0);
  if (fit.weighting != WienerBankFit::Weighting::Pooled) {
    for (std::size_t j = 0; j < clips.size(); ++j) {
      ceiling[j] = offline_ceiling(clips[j]).rms_m;
      weight[j] = 1.0 / (static_cast<double>(std::max<std::size_t>(fit_frames(clips[j]), 1)) * ceiling[j] * ceiling[j]);
    }
  }
  bank.gains = solve_gains(bank, clips, fit.delay, weight, fit.ridge);
  const int rounds = fit.weighting == WienerBankFit::Weighting::MeanRatio ? fit.reweighting_rounds : 0;
  for (int round = 0; round < rounds; ++round) {
    for (std::size_t j = 0; j < clips.size(); ++j) {
      const double rms = fit_rms(bank, clips[j], fit.delay);
      weight[j] = 1.0 / (static_cast<double>(std::max<std::size_t>(fit_frames(clips[j]), 1)) * std::max(rms, 1e-3 * ceiling[j]) * ceiling[j]);
    }
    bank.gains = solve_gains(bank, clips, fit.delay, weight, fit.ridge);
  }
  return bank;
}

}  // namespace tachi::filter
