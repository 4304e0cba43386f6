#include "tachi/filter/smoothing.hpp"
#include "tachi/filter/tremor_clips.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>

namespace tachi::filter {
namespace {

TEST(MovingAverage, MatchesHandComputedMeansWhileTheWindowFills) {
  MovingAverage avg{3};
  // Window 3 over 3, 6, 9, 12, 0: means 3, 4.5, 6, 9, 7 (computed by hand).
  const std::array<float, 5> in{3, 6, 9, 12, 0};
  const std::array<float, 5> expected{3.0F, 4.5F, 6.0F, 9.0F, 7.0F};
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3f out = avg.filter(Eigen::Vector3f{in[i], -in[i], 2 * in[i]});
    EXPECT_FLOAT_EQ(out.x(), expected[i]) << "sample " << i;
    EXPECT_FLOAT_EQ(out.y(), -expected[i]) << "sample " << i;
    EXPECT_FLOAT_EQ(out.z(), 2 * expected[i]) << "sample " << i;
  }
}

TEST(MovingAverage, ResetForgetsThePast) {
  MovingAverage avg{4};
  avg.filter(Eigen::Vector3f::Constant(10));
  avg.filter(Eigen::Vector3f::Constant(20));
  avg.reset();
  EXPECT_FLOAT_EQ(avg.filter(Eigen::Vector3f::Constant(1)).x(), 1.0F);
}

// Reference vectors: an independent Python implementation of Algorithm 1 of Casiez, Roussel, Vogel
// (CHI 2012) -- alpha = 1/(1 + tau/Te), tau = 1/(2 pi fc), dx = (x_i - x_hat_{i-1})/Te low-passed at
// d_cutoff, fc = min_cutoff + beta |dx_hat| -- plus the lag compensation (last case), run once on
// x = 0, 1, 1, 1, 0.5, 2, 2 and printed with 9 decimals (the script is in docs/filter.md).
struct OneEuroCase {
  OneEuroParams params;
  std::array<double, 7> t;
  std::array<double, 7> expected;
};

TEST(OneEuroScalar, MatchesIndependentReferenceVectors) {
  const std::array<double, 7> x{0.0, 1.0, 1.0, 1.0, 0.5, 2.0, 2.0};
  const std::array<OneEuroCase, 4> cases{{
      {{1.0, 0.5, 1.0, 0.0},
       {0, 1.0 / 30, 2.0 / 30, 3.0 / 30, 4.0 / 30, 5.0 / 30, 6.0 / 30},
       {0.000000000, 0.429702693, 0.710438559, 0.854887530, 0.712986093, 1.437326262, 1.766212441}},
      {{2.0, 0.0, 1.0, 0.0},
       {0, 0.02, 0.05, 0.1, 0.11, 0.2, 0.25},
       {0.000000000, 0.200848643, 0.419639425, 0.643582896, 0.627553989, 1.355953463, 1.604471407}},
      {{0.5, 10.0, 2.0, 0.0},
       {0, 1.0 / 30, 2.0 / 30, 3.0 / 30, 4.0 / 30, 5.0 / 30, 6.0 / 30},
       {0.000000000, 0.949119335, 0.996635230, 0.999695385, 0.648400077, 1.945014736, 1.997054949}},
      {{1.0, 3.0, 1.0, 1.0},
       {0, 1.0 / 30, 2.0 / 30, 3.0 / 30, 4.0 / 30, 5.0 / 30, 6.0 / 30},
       {0.000000000, 0.950033406, 1.025339931, 1.017157322, 0.652269630, 1.962741459, 2.023973484}},
  }};
  for (const auto& c : cases) {
    OneEuroScalar f{c.params};
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double dt = i == 0 ? 1.0 / 30 : c.t[i] - c.t[i - 1];
      EXPECT_NEAR(f.filter(x[i], dt), c.expected[i], 1e-8)
          << "min_cutoff " << c.params.min_cutoff_hz << " beta " << c.params.beta << " compensation "
          << c.params.lag_compensation << " sample " << i;
    }
  }
}

TEST(OneEuroScalar, AlphaFollowsTheCutoffFormula) {
  // fc = 1 Hz, Te = 1/30 s: tau = 1/(2 pi), alpha = 1/(1 + 30/(2 pi)) = 0.173171
  EXPECT_NEAR(one_euro_alpha(1.0, 1.0 / 30), 1.0 / (1.0 + 30.0 / (2.0 * 3.14159265358979)), 1e-12);
  EXPECT_NEAR(one_euro_alpha(1.0, 1.0 / 30), 0.173171, 1e-6);
}

TEST(OneEuroFilter, SmoothsMoreWhenSlowThanWhenFast) {
  // Held still with noise, the filter removes most jitter; moving fast, beta opens the cutoff.
  std::mt19937 rng{7};
  std::normal_distribution<float> noise{0.0F, 0.005F};
  OneEuroFilter still{{1.0, 1.0, 1.0, 0.0}};
  double raw_sq = 0, filtered_sq = 0;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3f n{noise(rng), noise(rng), noise(rng)};
    const Eigen::Vector3f out = still.filter(n, 1.0 / 30);
    if (i >= 30) {
      raw_sq += n.squaredNorm();
      filtered_sq += out.squaredNorm();
    }
  }
  EXPECT_LT(filtered_sq, 0.25 * raw_sq);

  OneEuroFilter fast{{1.0, 1.0, 1.0, 0.0}};
  OneEuroFilter no_beta{{1.0, 0.0, 1.0, 0.0}};
  Eigen::Vector3f a, b;
  for (int i = 0; i < 30; ++i) {  // 1.5 m/s ramp
    const Eigen::Vector3f x{0.05F * static_cast<float>(i), 0, 0};
    a = fast.filter(x, 1.0 / 30);
    b = no_beta.filter(x, 1.0 / 30);
  }
  const float target = 0.05F * 29;
  EXPECT_LT(target - a.x(), 0.5F * (target - b.x()));
}

TEST(OneEuroFilter, LagCompensationRemovesTheLagBehindAConstantVelocity) {
  // A hand moving at 0.2 m/s: the paper's filter trails it by about v * tau; compensated, it does not.
  const OneEuroParams paper{1.0, 0.0, 1.0, 0.0};
  const OneEuroParams compensated{1.0, 0.0, 1.0, 1.0};
  OneEuroScalar a{paper}, b{compensated};
  double x = 0, ya = 0, yb = 0;
  for (int i = 0; i < 300; ++i) {
    x = 0.2 * i / 30.0;
    ya = a.filter(x, 1.0 / 30);
    yb = b.filter(x, 1.0 / 30);
  }
  const double tau = 1.0 / (2.0 * 3.14159265358979);
  EXPECT_NEAR(x - ya, 0.2 * tau, 1e-3);  // ~32 mm behind
  EXPECT_NEAR(x - yb, 0.0, 1e-3);
}

TEST(Smoother, LongGapRestartsTheFilter) {
  SmootherParams p;
  p.kind = SmootherKind::MovingAverage;
  p.moving_average_window = 5;
  p.reset_after_gap_s = 0.5;
  Smoother s{p};
  s.filter(Eigen::Vector3f::Constant(1), 0);
  s.filter(Eigen::Vector3f::Constant(1), 33'000'000);
  // 1 s later: the old samples must not drag the new position.
  EXPECT_FLOAT_EQ(s.filter(Eigen::Vector3f::Constant(5), 1'033'000'000).x(), 5.0F);
}

TEST(Smoother, NoneReturnsTheInput) {
  SmootherParams p;
  p.kind = SmootherKind::None;
  Smoother s{p};
  s.filter({1, 2, 3}, 0);
  EXPECT_EQ(s.filter({4, 5, 6}, 33'000'000), Eigen::Vector3f(4, 5, 6));
}

TEST(SmootherParams, ValidationNamesTheBadKey) {
  SmootherParams p;
  p.one_euro.min_cutoff_hz = 0;
  ASSERT_TRUE(validate(p).has_value());
  EXPECT_NE(validate(p)->find("min_cutoff_hz"), std::string::npos);
  p = {};
  p.moving_average_window = 0;
  EXPECT_NE(validate(p)->find("window"), std::string::npos);
  EXPECT_FALSE(validate(SmootherParams{}).has_value());
}

}  // namespace
}  // namespace tachi::filter

// The Wiener smoother on randomized trembling hands it was not fitted on (held-out seeds
// 100001-100040; the taps were fitted on 1-1000), against the best offline zero-lag smoother of each clip.
// The full table (100001-100300) is in docs/filter.md. The target is 1.15x; what the default reaches
// is 1.46x (mean per clip over 300 clips); this test holds it there (1.55x on the smaller range; One Euro as
// configured by default measures 1.75x over the 300 and fails here), and the
// lag within one frame: it fails if the smoother regresses toward One Euro's 1.75x or starts to lag.
namespace {
struct HeldOutScore {
  double mean_vs_ceiling = 0.0;  ///< mean over the clips of the smoother's error over the ceiling's
  double median_lag_frames = 0.0;
};
/// A smoother of `kind` over the held-out tremor clips 100001-100040, as tachi-filter-bench --tremor scores it.
HeldOutScore held_out_score(tachi::filter::SmootherKind kind) {
  tachi::filter::SmootherParams params;
  params.kind = kind;
  std::vector<double> ratio, lag;
  for (std::uint64_t seed = 100001; seed <= 100040; ++seed) {
    const auto clip = tachi::filter::make_tremor_clip(seed);
    const auto ceiling = tachi::filter::offline_ceiling(clip);
    const auto score = tachi::filter::score_causal(clip, tachi::filter::run_smoother(clip, params));
    ratio.push_back(score.rms_m / ceiling.rms_m);
    lag.push_back(score.lag_frames);
  }
  std::sort(lag.begin(), lag.end());
  return {std::accumulate(ratio.begin(), ratio.end(), 0.0) / static_cast<double>(ratio.size()), lag[lag.size() / 2]};
}
}  // namespace

TEST(TremorClips, TheWienerSmootherStaysNearTheOfflineCeilingOnHeldOutClips) {
  const HeldOutScore score = held_out_score(tachi::filter::SmootherKind::Wiener);
  EXPECT_LE(score.mean_vs_ceiling, 1.55);
  EXPECT_LE(score.median_lag_frames, 1.0) << "median lag";
}

// The Wiener bank (wiener-bank) on the same held-out clips: the bank of FIRs chosen by what the last 12 samples
// show, fitted on seeds 1-1000. Over the 300 held-out clips it is 1.142x the ceiling (mean per clip; the target
// is 1.15x, docs/filter.md); on these 40 it measured 1.122x (1.51x for the single FIR; 1.14x for the bank
// fitted to the pooled error before session 31). It fails if the scheduling stops paying (back toward the
// single FIR) or the smoother starts to lag.
TEST(TremorClips, TheWienerBankComesNearerTheOfflineCeilingOnHeldOutClips) {
  const HeldOutScore score = held_out_score(tachi::filter::SmootherKind::WienerBank);
  EXPECT_LE(score.mean_vs_ceiling, 1.18) << "mean per clip / ceiling";
  EXPECT_LE(score.median_lag_frames, 1.0) << "median lag";
}

// The bank in wiener_bank_table.cpp is what its command fits (tachi-filter-bench --fit-wiener-bank 1..1000, with
// WienerBankFit's defaults): regenerate the table when the clips, the features or the fit change.
TEST(WienerBank, TheBankInTheSourceIsTheFitOfTheTuningClips) {
  std::vector<tachi::filter::TremorClip> clips;
  for (std::uint64_t seed = 1; seed <= 1000; ++seed) clips.push_back(tachi::filter::make_tremor_clip(seed));
  const auto fitted = tachi::filter::fit_wiener_bank(clips, tachi::filter::WienerBankFit{});
  const auto& shipped = tachi::filter::tremor_wiener_bank();
  ASSERT_EQ(shipped.bins(), fitted.bins());
  const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b)); };
  for (std::size_t d = 0; d < shipped.centres.size(); ++d) {
    for (std::size_t b = 0; b < shipped.centres[d].size(); ++b) {
      EXPECT_TRUE(near(shipped.centres[d][b], fitted.centres[d][b])) << "feature " << d << " centre " << b;
    }
  }
  for (std::size_t b = 0; b < shipped.bins(); ++b) {
    for (std::size_t k = 0; k < shipped.gains[b].size(); ++k) {
      EXPECT_TRUE(near(shipped.gains[b][k], fitted.gains[b][k])) << "bin " << b << " gain " << k;
    }
  }
}

// The taps are interpolated between the bins' centres: swept finely across every centre of each feature,
// they never jump (a choice of one bin by thresholds would jump by the difference between neighbouring bins'
// gains at each boundary), and a still hand, whatever bin its features fall in, stays where it is.
TEST(WienerBank, TheTapsMoveContinuouslyWithTheFeaturesAndAStillHandStaysPut) {
  const auto& bank = tachi::filter::tremor_wiener_bank();
  for (std::size_t d = 0; d < 3; ++d) {
    std::array<double, 3> f{bank.centres[0][2], bank.centres[1][2], bank.centres[2][2]};
    const double lo = bank.centres[d].front() - 0.2, hi = bank.centres[d].back() + 0.2;
    std::array<double, 11> previous{};
    double largest_step = 0.0;
    constexpr int kSteps = 20000;
    for (int i = 0; i <= kSteps; ++i) {
      f[d] = lo + (hi - lo) * i / kSteps;
      const auto w = tachi::filter::bin_weights(bank, f);
      EXPECT_NEAR(std::accumulate(w.weight.begin(), w.weight.end(), 0.0), 1.0, 1e-12);
      std::array<double, 11> gains{};
      for (std::size_t c = 0; c < 8; ++c)
        for (std::size_t k = 0; k < 11; ++k) gains[k] += w.weight[c] * bank.gains[w.bin[c]][k];
      if (i > 0)
        for (std::size_t k = 0; k < 11; ++k) largest_step = std::max(largest_step, std::abs(gains[k] - previous[k]));
      previous = gains;
    }
    EXPECT_LT(largest_step, 1e-3) << "feature " << d;  // measured <= 5.3e-5
  }
  tachi::filter::BankedWiener filter{bank};
  std::optional<Eigen::Vector3f> out;
  for (int i = 0; i < 12; ++i) out = filter.filter({0.1F, -0.2F, 1.0F});
  ASSERT_TRUE(out.has_value());
  EXPECT_TRUE(out->isApprox(Eigen::Vector3f{0.1F, -0.2F, 1.0F}, 1e-5F));
}

TEST(TremorClips, AClipIsTheSameForTheSameSeedAndItsTremorIsInTheDrawnBand) {
  const auto a = tachi::filter::make_tremor_clip(7), b = tachi::filter::make_tremor_clip(7);
  ASSERT_EQ(a.measured.size(), b.measured.size());
  EXPECT_TRUE(a.measured.back().isApprox(b.measured.back()));
  EXPECT_GE(a.tremor_hz, 4.0);
  EXPECT_LE(a.tremor_hz, 12.0);
  // The offline ceiling beats the raw samples (it is a smoother with the best width for this clip).
  EXPECT_LT(tachi::filter::offline_ceiling(a).rms_m, tachi::filter::rms_against_shifted(a, a.measured, 0.0));
}

TEST(WienerFir, TapsSumToOneSoAStillHandStaysPut) {
  const auto& taps = tachi::filter::tremor_wiener_taps();
  EXPECT_NEAR(std::accumulate(taps.begin(), taps.end(), 0.0), 1.0, 1e-5);
  tachi::filter::WienerFir fir{taps};
  std::optional<Eigen::Vector3f> out;
  for (std::size_t i = 0; i < taps.size(); ++i) {
    EXPECT_FALSE(out.has_value());
    out = fir.filter({0.1F, -0.2F, 1.0F});
  }
  ASSERT_TRUE(out.has_value());
  EXPECT_TRUE(out->isApprox(Eigen::Vector3f{0.1F, -0.2F, 1.0F}, 1e-5F));
}
