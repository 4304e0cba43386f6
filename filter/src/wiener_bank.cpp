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

WienerBank fit_wiener_bank(const std::vector<TremorClip>& clips, std::size_t bins, double delay) {
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
    for (std::size_t b = 0; b < bins; ++b) {
      bank.centres[d].push_back(values[d][std::min(values[d].size() - 1, (2 * b + 1) * values[d].size() / (2 * bins))]);
    }
  }
  // The normal equations of every bin's gains at once: a frame's prediction is sum_c w_c (g_c . r) per axis.
  const std::size_t unknowns = bank.bins() * kGains;
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(unknowns), static_cast<Eigen::Index>(unknowns));
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(unknowns));
  Eigen::Matrix<double, kGains, kGains> all_ata = Eigen::Matrix<double, kGains, kGains>::Zero();
  Eigen::Matrix<double, kGains, 1> all_atb = Eigen::Matrix<double, kGains, 1>::Zero();
  for (const auto& c : clips) {
    const std::size_t frames = c.measured.size();
    for (std::size_t i = std::max(kScoreMargin, WienerBank::kTaps); i + kScoreMargin < frames; ++i) {
      const double t = static_cast<double>(i) - delay;
      const auto f = static_cast<std::size_t>(std::floor(t));
      const double w = t - static_cast<double>(f);
      const Eigen::Vector3d target = (1 - w) * c.intended[f] + w * c.intended[f + 1] - c.measured[i];
      Eigen::Matrix<double, kGains, kGains> rr = Eigen::Matrix<double, kGains, kGains>::Zero();
      Eigen::Matrix<double, kGains, 1> rt = Eigen::Matrix<double, kGains, 1>::Zero();
      for (int a = 0; a < 3; ++a) {
        Eigen::Matrix<double, kGains, 1> row;
        for (std::size_t k = 1; k <= kGains; ++k) row[static_cast<Eigen::Index>(k - 1)] = c.measured[i - k][a] - c.measured[i][a];
        rr += row * row.transpose();
        rt += row * target[a];
      }
      all_ata += rr;
      all_atb += rt;
      const BinWeights bw = bin_weights(bank, features_at(c.measured, i));
      for (std::size_t p = 0; p < 8; ++p) {
        if (bw.weight[p] == 0.0) continue;
        const auto at_p = static_cast<Eigen::Index>(bw.bin[p] * kGains);
        atb.segment<kGains>(at_p) += bw.weight[p] * rt;
        for (std::size_t q = 0; q < 8; ++q) {
          if (bw.weight[q] == 0.0) continue;
          const auto at_q = static_cast<Eigen::Index>(bw.bin[q] * kGains);
          ata.block<kGains, kGains>(at_p, at_q) += bw.weight[p] * bw.weight[q] * rr;
        }
      }
    }
  }
  // The ridge: 1e-3 of the mean diagonal, toward the one FIR over all the frames.
  const Eigen::Matrix<double, kGains, 1> global = all_ata.ldlt().solve(all_atb);
  const double ridge = 1e-3 * ata.diagonal().mean();
  for (std::size_t b = 0; b < bank.bins(); ++b) {
    const auto at = static_cast<Eigen::Index>(b * kGains);
    ata.block<kGains, kGains>(at, at) += ridge * Eigen::Matrix<double, kGains, kGains>::Identity();
    atb.segment<kGains>(at) += ridge * global;
  }
  const Eigen::VectorXd g = ata.ldlt().solve(atb);
  bank.gains.resize(bank.bins());
  for (std::size_t b = 0; b < bank.bins(); ++b) {
    for (std::size_t k = 0; k < kGains; ++k) bank.gains[b][k] = g[static_cast<Eigen::Index>(b * kGains + k)];
  }
  return bank;
}

}  // namespace tachi::filter
