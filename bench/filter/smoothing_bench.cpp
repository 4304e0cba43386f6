// Smoothing benchmark on a jittery recording with a known intended path (recordings/jitter: hand tremor
// 6 mm RMS per axis at 4-9 Hz over a slow diagonal cut). For raw, moving average (N = 3, 5, 9) and One Euro
// it prints the RMS 3D error against the intended path, the lag in frames (the shift of the intended path
// that minimises the error, searched in 0.05-frame steps) and the error once that lag is removed.
// Baseline: the raw samples in the same run. See docs/benchmarks.md for the commands and results.
#include "tachi/common/app.hpp"
#include "tachi/filter/hand_csv.hpp"
#include "tachi/filter/smoothing.hpp"
#include "tachi/filter/tremor_clips.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <algorithm>
#include <numeric>
#include <tuple>

namespace {

using tachi::filter::HandSample;

struct Truth {
  std::map<std::uint64_t, Eigen::Vector3d> intended;
  std::map<std::uint64_t, Eigen::Vector3d> palm;
  std::map<std::uint64_t, bool> visible;
};

Truth read_truth(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::string line;
  std::getline(in, line);
  std::map<std::string, std::size_t> col;
  {
    std::stringstream h(line);
    std::string c;
    for (std::size_t i = 0; std::getline(h, c, ','); ++i) col[c] = i;
  }
  for (const char* need : {"frame", "x", "y", "z", "visible", "intended_x", "intended_y", "intended_z"})
    if (!col.contains(need)) throw std::runtime_error(path + ": no column " + need + " (a ground_truth.csv with intended_*)");
  Truth t;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string c;
    while (std::getline(s, c, ',')) cells.push_back(c);
    if (cells.size() < col.size()) continue;
    const auto f = std::stoull(cells[col["frame"]]);
    t.intended[f] = {std::stod(cells[col["intended_x"]]), std::stod(cells[col["intended_y"]]), std::stod(cells[col["intended_z"]])};
    t.palm[f] = {std::stod(cells[col["x"]]), std::stod(cells[col["y"]]), std::stod(cells[col["z"]])};
    t.visible[f] = cells[col["visible"]] == "1";
  }
  return t;
}

/// The intended path at a fractional frame (linear between frames; the path is smooth at 30 Hz).
std::optional<Eigen::Vector3d> intended_at(const Truth& t, double frame) {
  const auto f0 = static_cast<std::uint64_t>(std::floor(frame));
  const auto a = t.intended.find(f0), b = t.intended.find(f0 + 1);
  if (frame < 0 || a == t.intended.end() || b == t.intended.end()) return std::nullopt;
  const double w = frame - static_cast<double>(f0);
  return (1 - w) * a->second + w * b->second;
}

struct Score {
  double rms_mm = 0;
  double lag_frames = 0;
  double rms_at_lag_mm = 0;
};

Score score(const Truth& t, const std::vector<std::pair<std::uint64_t, Eigen::Vector3d>>& out) {
  const auto rms_at = [&](double shift) {
    double sum = 0;
    std::size_t n = 0;
    for (const auto& [frame, p] : out) {
      const auto q = intended_at(t, static_cast<double>(frame) - shift);
      if (!q) continue;
      sum += (p - *q).squaredNorm();
      ++n;
    }
    return n == 0 ? INFINITY : std::sqrt(sum / static_cast<double>(n)) * 1000.0;
  };
  Score s;
  s.rms_mm = rms_at(0.0);
  s.rms_at_lag_mm = INFINITY;
  for (double shift = -3.0; shift <= 15.0; shift += 0.05) {
    const double r = rms_at(shift);
    if (r < s.rms_at_lag_mm) {
      s.rms_at_lag_mm = r;
      s.lag_frames = shift;
    }
  }
  return s;
}

/// Runs a smoother over the tracked samples (a lost hand resets it, as in the filter stage) and keeps the
/// frames in which the hand was tracked and visible.
std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> run(const std::vector<HandSample>& hands, const Truth& t,
                                                            const tachi::filter::SmootherParams& p, double max_speed) {
  tachi::filter::Smoother smoother{p};
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> out;
  for (const auto& h : hands) {
    if (!h.tracked) {
      smoother.reset();
      continue;
    }
    const Eigen::Vector3f y = smoother.filter(h.position_m, h.stamp_ns);
    const auto v = t.visible.find(h.frame);
    if (v == t.visible.end() || !v->second) continue;
    // Score the stroke itself: not the reach into view (~3 m/s) nor the drop out of it.
    const auto a = t.intended.find(h.frame), b = t.intended.find(h.frame + 1);
    if (a == t.intended.end() || b == t.intended.end() || (b->second - a->second).norm() * 30.0 > max_speed) continue;
    out.emplace_back(h.frame, y.cast<double>());
  }
  return out;
}


/// "FIRST..LAST" -> the seed range.
std::pair<std::uint64_t, std::uint64_t> parse_range(const std::string& text) {
  const auto dots = text.find("..");
  if (dots == std::string::npos) throw std::invalid_argument("--tremor " + text + ": expected FIRST..LAST (e.g. 100001..100300)");
  const auto first = std::stoull(text.substr(0, dots)), last = std::stoull(text.substr(dots + 2));
  if (last < first) throw std::invalid_argument("--tremor " + text + ": LAST is below FIRST");
  return {first, last};
}

struct TremorSet {
  std::vector<tachi::filter::TremorClip> clips;
  std::vector<double> ceiling_m, raw_m;
};

TremorSet make_set(std::uint64_t first, std::uint64_t last) {
  TremorSet set;
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    set.clips.push_back(tachi::filter::make_tremor_clip(seed));
    set.ceiling_m.push_back(tachi::filter::offline_ceiling(set.clips.back()).rms_m);
    set.raw_m.push_back(tachi::filter::rms_against_shifted(set.clips.back(), set.clips.back().measured, 0.0));
  }
  return set;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

struct TremorResult {
  double mean_vs_ceiling = 0, median_vs_ceiling = 0, p90_vs_ceiling = 0, pooled_vs_ceiling = 0, pooled_vs_raw = 0;
  double lag_median = 0, lag_p95 = 0, lag_max = 0, same_frame_vs_ceiling = 0;
};

/// Scores, clip by clip, what `smooth(i)` makes of clip i against the clip's ceiling.
template <typename Smooth>
TremorResult evaluate_outputs(const TremorSet& set, const Smooth& smooth) {
  std::vector<double> ratio, lag;
  double err2 = 0, ceil2 = 0, raw2 = 0, same2 = 0;
  for (std::size_t i = 0; i < set.clips.size(); ++i) {
    const auto s = tachi::filter::score_causal(set.clips[i], smooth(i));
    ratio.push_back(s.rms_m / set.ceiling_m[i]);
    lag.push_back(s.lag_frames);
    err2 += s.rms_m * s.rms_m;
    same2 += s.rms_same_frame_m * s.rms_same_frame_m;
    ceil2 += set.ceiling_m[i] * set.ceiling_m[i];
    raw2 += set.raw_m[i] * set.raw_m[i];
  }
  TremorResult r;
  r.mean_vs_ceiling = std::accumulate(ratio.begin(), ratio.end(), 0.0) / static_cast<double>(ratio.size());
  r.median_vs_ceiling = quantile(ratio, 0.5);
  r.p90_vs_ceiling = quantile(ratio, 0.9);
  r.pooled_vs_ceiling = std::sqrt(err2 / ceil2);
  r.pooled_vs_raw = std::sqrt(err2 / raw2);
  r.same_frame_vs_ceiling = std::sqrt(same2 / ceil2);
  r.lag_median = quantile(lag, 0.5);
  r.lag_p95 = quantile(lag, 0.95);
  r.lag_max = quantile(lag, 1.0);
  return r;
}

TremorResult evaluate(const TremorSet& set, const tachi::filter::SmootherParams& p) {
  return evaluate_outputs(set, [&](std::size_t i) { return tachi::filter::run_smoother(set.clips[i], p); });
}

void print_tremor_header() {
  std::printf("%-58s %9s %9s %9s %9s %9s %8s %8s %8s %10s\n", "smoother", "mean/ceil", "med/ceil", "p90/ceil", "pool/ceil",
              "pool/raw", "lag_med", "lag_p95", "lag_max", "same_fr/ce");
}

void print_tremor_row(const std::string& label, const TremorResult& r) {
  std::printf("%-58s %9.3f %9.3f %9.3f %9.3f %9.3f %8.2f %8.2f %8.2f %10.3f\n", label.c_str(), r.mean_vs_ceiling,
              r.median_vs_ceiling, r.p90_vs_ceiling, r.pooled_vs_ceiling, r.pooled_vs_raw, r.lag_median, r.lag_p95,
              r.lag_max, r.same_frame_vs_ceiling);
}


/// The Wiener FIR (least squares on training clips): out_n = y_n + sum_k g_k (y_{n-k} - y_n), k = 1..taps-1,
/// fitted to intended_{n - delay}; translation invariant (the taps sum to 1).
std::vector<double> fit_fir(const TremorSet& set, int taps, double delay) {
  const int m = taps - 1;
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(m);
  for (const auto& c : set.clips) {
    const int n = static_cast<int>(c.measured.size());
    for (int i = std::max<int>(taps, tachi::filter::kScoreMargin); i < n - static_cast<int>(tachi::filter::kScoreMargin); ++i) {
      const double t = i - delay;
      const int f = static_cast<int>(std::floor(t));
      const double w = t - f;
      const Eigen::Vector3d target = (1 - w) * c.intended[f] + w * c.intended[f + 1] - c.measured[i];
      for (int a = 0; a < 3; ++a) {
        Eigen::VectorXd row(m);
        for (int k = 1; k <= m; ++k) row[k - 1] = c.measured[i - k][a] - c.measured[i][a];
        ata += row * row.transpose();
        atb += row * target[a];
      }
    }
  }
  const Eigen::VectorXd g = ata.ldlt().solve(atb);
  std::vector<double> h(static_cast<std::size_t>(taps));
  h[0] = 1.0 - g.sum();
  for (int k = 1; k <= m; ++k) h[static_cast<std::size_t>(k)] = g[k - 1];
  return h;
}

/// Fits the Wiener taps on the clips of `range` and prints them (paste into smoothing.cpp).
int fit_wiener(std::pair<std::uint64_t, std::uint64_t> range, int taps, double delay) {
  TremorSet set;
  for (std::uint64_t seed = range.first; seed <= range.second; ++seed) set.clips.push_back(tachi::filter::make_tremor_clip(seed));
  const auto h = fit_fir(set, taps, delay);
  std::printf("wiener taps (%d, newest first, delay %.2f frame, clips %llu..%llu):", taps, delay,
              static_cast<unsigned long long>(range.first), static_cast<unsigned long long>(range.second));
  for (std::size_t k = 0; k < h.size(); ++k) std::printf("%s %.6f", k ? "," : "", h[k]);
  std::printf("\n");
  return 0;
}

/// A causal FIR `h` (newest first) over the clip's measured samples; the first taps - 1 frames pass raw.
std::vector<Eigen::Vector3d> apply_fir(const tachi::filter::TremorClip& clip, const std::vector<double>& h) {
  std::vector<Eigen::Vector3d> out = clip.measured;
  for (std::size_t n = h.size() - 1; n < clip.measured.size(); ++n) {
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < h.size(); ++k) acc += h[k] * clip.measured[n - k];
    out[n] = acc;
  }
  return out;
}

/// The causal FIR's least-squares normal equations (translation-invariant form of fit_fir) for frame i of a
/// clip, per axis, added with weight `weight` to rows [at, at + 11) of `ata` / `atb`.
void add_fir_rows(const tachi::filter::TremorClip& c, int i, double delay, double weight, Eigen::Index at,
                  Eigen::MatrixXd& ata, Eigen::VectorXd& atb) {
  const double t = i - delay;
  const int f = static_cast<int>(std::floor(t));
  const double w = t - f;
  const Eigen::Vector3d target = (1 - w) * c.intended[f] + w * c.intended[f + 1] - c.measured[i];
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd row(11);
    for (int k = 1; k <= 11; ++k) row[k - 1] = c.measured[i - k][a] - c.measured[i][a];
    ata.block(at, at, 11, 11) += weight * row * row.transpose();
    atb.segment(at, 11) += weight * row * target[a];
  }
}

/// A 12-tap FIR in fit_fir's form (out = y_n + sum_k g_k (y_{n-k} - y_n)), chosen per frame by `taps_at(n)`.
template <typename TapsAt>
std::vector<Eigen::Vector3d> apply_scheduled(const std::vector<Eigen::Vector3d>& y, const TapsAt& taps_at) {
  std::vector<Eigen::Vector3d> out = y;
  for (int n = 12; n < static_cast<int>(y.size()); ++n) {
    const Eigen::VectorXd& g = taps_at(n);
    Eigen::Vector3d acc = y[n];
    for (int k = 1; k <= 11; ++k) acc += g[k - 1] * (y[n - k] - y[n]);
    out[n] = acc;
  }
  return out;
}

/// A bank's scheduled FIR over the clip's measured samples (the raw samples until its history is full).
std::vector<Eigen::Vector3d> apply_bank(const tachi::filter::TremorClip& clip, const tachi::filter::WienerBank& bank) {
  tachi::filter::BankedWiener filter{bank};
  std::vector<Eigen::Vector3d> out = clip.measured;
  for (std::size_t n = 0; n < out.size(); ++n) {
    if (const auto y = filter.filter(clip.measured[n].cast<float>())) out[n] = y->cast<double>();
  }
  return out;
}

/// How close a causal 12-tap FIR (at most ~1 frame of delay) can come to the ceiling, and how much of that
/// adapting to the hand buys, on the clips of `range`; the banks are fitted on the tuning seeds 1..1000:
/// - each clip's own least-squares FIR: an oracle that knows the clip's truth (and, fitted on the clip's
///   first half, how much of that is the fit learning the clip's noise). For roughly Gaussian signals the
///   causal MMSE estimator is linear (Wiener 1949), so this bounds adapting a linear filter to the hand;
/// - a bank of FIRs, one per bin of the clip's drawn speed, tremor frequency and amplitude, chosen by them
///   (the choice is an oracle);
/// - the wiener-bank smoother's bank (wiener_bank.hpp), fitted in this run on 1..1000 with 3-5 centres per
///   feature: what the scheduling buys without an oracle.
int oracle_fir(std::pair<std::uint64_t, std::uint64_t> range) {
  const TremorSet set = make_set(range.first, range.second);
  std::printf("tremor clips %llu..%llu (%zu): causal 12-tap FIRs adapted to the hand (docs/filter.md)\n",
              static_cast<unsigned long long>(range.first), static_cast<unsigned long long>(range.second), set.clips.size());
  print_tremor_header();
  for (const double delay : {0.5, 0.9, 1.0}) {
    const auto result = evaluate_outputs(set, [&](std::size_t i) {
      TremorSet one;
      one.clips.push_back(set.clips[i]);
      return apply_fir(set.clips[i], fit_fir(one, 12, delay));
    });
    char label[96];
    std::snprintf(label, sizeof label, "each clip's own FIR (oracle), delay %.1f frame", delay);
    print_tremor_row(label, result);
  }
  print_tremor_row("each clip's own FIR fitted on its first half, delay 0.9", evaluate_outputs(set, [&](std::size_t i) {
                     TremorSet one;
                     tachi::filter::TremorClip first = set.clips[i];
                     const std::size_t n = first.measured.size() / 2 + tachi::filter::kScoreMargin;
                     first.measured.resize(n);
                     first.intended.resize(n);
                     one.clips.push_back(first);
                     return apply_fir(set.clips[i], fit_fir(one, 12, 0.9));
                   }));
  TremorSet tuning;
  for (std::uint64_t seed = 1; seed <= 1000; ++seed) tuning.clips.push_back(tachi::filter::make_tremor_clip(seed));
  constexpr double kDelay = 0.9;
  // Bins of the drawn parameters: speed 0.03-1.2 m/s and amplitude 1-8 mm log-spaced, frequency 4-12 Hz.
  const auto drawn_bin = [](const tachi::filter::TremorClip& c, int speeds, int freqs, int amps) {
    const auto at = [](double x, double lo, double hi, int n) {
      return std::clamp(static_cast<int>(std::floor((x - lo) / (hi - lo) * n)), 0, n - 1);
    };
    return (at(std::log(c.speed_mps), std::log(0.03), std::log(1.2), speeds) * freqs + at(c.tremor_hz, 4.0, 12.0, freqs)) * amps +
           at(std::log(c.tremor_rms_m), std::log(0.001), std::log(0.008), amps);
  };
  for (const auto& [speeds, freqs, amps] : std::vector<std::tuple<int, int, int>>{{1, 4, 1}, {3, 4, 3}}) {
    const int bins = speeds * freqs * amps;
    std::vector<Eigen::MatrixXd> ata(bins, Eigen::MatrixXd::Zero(11, 11));
    std::vector<Eigen::VectorXd> atb(bins, Eigen::VectorXd::Zero(11));
    for (const auto& c : tuning.clips) {
      const int b = drawn_bin(c, speeds, freqs, amps);
      for (int i = tachi::filter::kScoreMargin; i < static_cast<int>(c.measured.size()) - static_cast<int>(tachi::filter::kScoreMargin); ++i)
        add_fir_rows(c, i, kDelay, 1.0, 0, ata[b], atb[b]);
    }
    std::vector<Eigen::VectorXd> g(bins);
    for (int b = 0; b < bins; ++b) g[b] = (ata[b] + 1e-12 * Eigen::MatrixXd::Identity(11, 11)).ldlt().solve(atb[b]);
    char label[96];
    std::snprintf(label, sizeof label, "bank by drawn speed x freq x amp %dx%dx%d (oracle choice)", speeds, freqs, amps);
    print_tremor_row(label, evaluate_outputs(set, [&](std::size_t i) {
                       const Eigen::VectorXd& taps = g[static_cast<std::size_t>(drawn_bin(set.clips[i], speeds, freqs, amps))];
                       return apply_scheduled(set.clips[i].measured, [&](int) -> const Eigen::VectorXd& { return taps; });
                     }));
  }
  for (const std::size_t bins : {3, 4, 5}) {
    const std::vector<tachi::filter::TremorClip> clips(tuning.clips.begin(), tuning.clips.end());
    tachi::filter::WienerBankFit fit;
    fit.bins = bins;
    const tachi::filter::WienerBank bank = tachi::filter::fit_wiener_bank(clips, fit);
    char label[96];
    std::snprintf(label, sizeof label, "wiener-bank, %zu centres a feature (fitted on 1..1000 now)", bins);
    print_tremor_row(label, evaluate_outputs(set, [&](std::size_t i) { return apply_bank(set.clips[i], bank); }));
    std::fflush(stdout);
  }
  return 0;
}

const char* to_string(tachi::filter::WienerBankFit::Weighting weighting) {
  using W = tachi::filter::WienerBankFit::Weighting;
  return weighting == W::Pooled ? "pooled" : weighting == W::Ceiling ? "ceiling" : "mean-ratio";
}

/// Fits the wiener-bank smoother's bank on the clips of `range` and prints it as the source of
/// filter/src/wiener_bank_table.cpp (what tremor_wiener_bank() returns); with a `validate` range, prints instead
/// the fitted bank's row of the --tremor table on those clips (choosing a fit on the validation seeds).
int fit_wiener_bank(std::pair<std::uint64_t, std::uint64_t> range, const tachi::filter::WienerBankFit& fit,
                    const std::string& validate) {
  std::vector<tachi::filter::TremorClip> clips;
  for (std::uint64_t seed = range.first; seed <= range.second; ++seed) clips.push_back(tachi::filter::make_tremor_clip(seed));
  const tachi::filter::WienerBank bank = tachi::filter::fit_wiener_bank(clips, fit);
  if (!validate.empty()) {
    const auto [first, last] = parse_range(validate);
    const TremorSet set = make_set(first, last);
    char label[96];
    std::snprintf(label, sizeof label, "wiener-bank %zu %s x%d ridge %.0e delay %.2f", fit.bins, to_string(fit.weighting),
                  fit.reweighting_rounds, fit.ridge, fit.delay);
    print_tremor_header();
    print_tremor_row(label, evaluate_outputs(set, [&](std::size_t i) { return apply_bank(set.clips[i], bank); }));
    return 0;
  }
  std::printf("// Generated by `tachi-filter-bench --fit-wiener-bank %llu..%llu --bins %zu --delay %.2f --ridge %g --weighting %s%s`\n"
              "// (docs/filter.md); a test checks that the fit still gives it. The wiener-bank smoother's bank (wiener_bank.hpp).\n"
              "#include \"tachi/filter/wiener_bank.hpp\"\n\nnamespace tachi::filter {\n\nconst WienerBank& tremor_wiener_bank() {\n"
              "  static const WienerBank bank{\n      {{\n",
              static_cast<unsigned long long>(range.first), static_cast<unsigned long long>(range.second), fit.bins, fit.delay,
              fit.ridge, to_string(fit.weighting),
              fit.weighting == tachi::filter::WienerBankFit::Weighting::MeanRatio
                  ? (" --rounds " + std::to_string(fit.reweighting_rounds)).c_str() : "");
  for (const auto& centres : bank.centres) {
    std::printf("          {");
    for (std::size_t b = 0; b < centres.size(); ++b) std::printf("%s%.9g", b ? ", " : "", centres[b]);
    std::printf("},\n");
  }
  std::printf("      }},\n      {\n");
  for (const auto& g : bank.gains) {
    std::printf("          {");
    for (std::size_t k = 0; k < g.size(); ++k) std::printf("%s%.9g", k ? ", " : "", g[k]);
    std::printf("},\n");
  }
  std::printf("      }};\n  return bank;\n}\n\n}  // namespace tachi::filter\n");
  return 0;
}

tachi::filter::SmootherParams with_kind(tachi::filter::SmootherKind kind) {
  tachi::filter::SmootherParams p;
  p.kind = kind;
  return p;
}

std::string one_euro_label(const char* what, const tachi::filter::OneEuroParams& e) {
  char name[160];
  std::snprintf(name, sizeof name, "one-euro %s (%.2f Hz, beta %.1f, d %.1f Hz, comp %.2f)", what, e.min_cutoff_hz, e.beta,
                e.d_cutoff_hz, e.lag_compensation);
  return name;
}

int tremor_table(std::pair<std::uint64_t, std::uint64_t> range, const tachi::filter::OneEuroParams& chosen) {
  using tachi::filter::SmootherKind;
  const TremorSet set = make_set(range.first, range.second);
  std::printf("tremor clips %llu..%llu (%zu): raw %.2f mm, ceiling %.2f mm (pooled RMS against the intended path)\n",
              static_cast<unsigned long long>(range.first), static_cast<unsigned long long>(range.second), set.clips.size(),
              1000 * std::sqrt(std::inner_product(set.raw_m.begin(), set.raw_m.end(), set.raw_m.begin(), 0.0) / static_cast<double>(set.raw_m.size())),
              1000 * std::sqrt(std::inner_product(set.ceiling_m.begin(), set.ceiling_m.end(), set.ceiling_m.begin(), 0.0) / static_cast<double>(set.ceiling_m.size())));
  print_tremor_header();
  print_tremor_row("raw", evaluate(set, with_kind(SmootherKind::None)));
  auto ma = with_kind(SmootherKind::MovingAverage);
  ma.moving_average_window = 3;
  print_tremor_row("moving average N=3", evaluate(set, ma));
  tachi::filter::SmootherParams p;
  p.kind = SmootherKind::OneEuro;
  print_tremor_row(one_euro_label("(the default)", p.one_euro), evaluate(set, p));
  p.one_euro = chosen;
  print_tremor_row(one_euro_label("given", p.one_euro), evaluate(set, p));
  p.kind = SmootherKind::Wiener;
  print_tremor_row("wiener (12 taps fitted on seeds 1..1000)", evaluate(set, p));
  p.kind = SmootherKind::WienerBank;
  print_tremor_row("wiener-bank (5^3 bins fitted on seeds 1..1000)", evaluate(set, p));
  return 0;
}

int tune(std::pair<std::uint64_t, std::uint64_t> range) {
  const TremorSet set = make_set(range.first, range.second);
  print_tremor_header();
  tachi::filter::SmootherParams p;
  p.kind = tachi::filter::SmootherKind::OneEuro;
  for (double comp : {0.0, 0.5, 1.0})
    for (double d : {0.5, 1.0, 2.0})
      for (double fc : {0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0})
        for (double b : {0.0, 2.0, 5.0, 10.0, 20.0, 40.0}) {
          p.one_euro = {fc, b, d, comp};
          print_tremor_row(one_euro_label("", p.one_euro), evaluate(set, p));
          std::fflush(stdout);
        }
  return 0;
}
}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-filter-bench: smoothing error and lag against a recording's intended path"};
  app.name("tachi-filter-bench");
  std::string hands_csv, truth_csv;
  double min_cutoff = -1, beta = -1, d_cutoff = -1, lag_compensation = -1, max_speed = 0.5;
  app.add_option("--lag-compensation", lag_compensation, "One Euro lag_compensation (0 = the paper's filter) to try");
  app.add_option("--hands", hands_csv, "tachi-sensor's CSV for the recording (omit: use the ground-truth palm, tremor only)")
      ->check(CLI::ExistingFile);
  app.add_option("--truth", truth_csv, "The recording's ground_truth.csv (with intended_x,y,z); needed unless --tremor, --tune, --fit-wiener, "
                 "--fit-wiener-bank or --oracle-fir")
      ->check(CLI::ExistingFile);
  std::string tremor_range, tune_range;
  app.add_option("--tremor", tremor_range,
                 "Randomized trembling-hand clips FIRST..LAST (held out: 100001..100300): each smoother's error against "
                 "the best offline zero-lag smoother of the same clip (the ceiling), and its lag");
  std::string fit_range;
  int taps = 12;
  double delay = 0.9;
  app.add_option("--fit-wiener", fit_range, "Fit the Wiener smoother's taps on clips FIRST..LAST (tuning: 1..1000) and print them");
  app.add_option("--taps", taps, "With --fit-wiener: the number of taps")->capture_default_str()->check(CLI::Range(2, 64));
  app.add_option("--delay", delay,
                 "With --fit-wiener or --fit-wiener-bank: the intended path's delay the taps aim at (frames; 0.9 for "
                 "--fit-wiener, WienerBankFit's for --fit-wiener-bank)")
      ->check(CLI::Range(0.0, 5.0));
  app.add_option("--tune", tune_range, "Grid-search the One Euro parameters on clips FIRST..LAST (tuning: 1..1000)");
  std::string oracle_range, bank_range;
  tachi::filter::WienerBankFit bank_fit;
  std::string bank_weighting = to_string(bank_fit.weighting), bank_validate;
  app.add_option("--fit-wiener-bank", bank_range,
                 "Fit the wiener-bank smoother's bank on clips FIRST..LAST (tuning: 1..1000) and print it as "
                 "filter/src/wiener_bank_table.cpp");
  app.add_option("--bins", bank_fit.bins, "With --fit-wiener-bank: centres per feature")->capture_default_str()->check(CLI::Range(2, 12));
  app.add_option("--weighting", bank_weighting,
                 "With --fit-wiener-bank: how the clips count (pooled: every frame alike; ceiling: each clip by 1 / "
                 "its ceiling^2; mean-ratio: that, then reweighted toward the mean of RMS / ceiling)")
      ->capture_default_str()->check(CLI::IsMember({"pooled", "ceiling", "mean-ratio"}));
  app.add_option("--rounds", bank_fit.reweighting_rounds, "With --weighting mean-ratio: reweighting rounds")
      ->capture_default_str()->check(CLI::Range(0, 20));
  app.add_option("--ridge", bank_fit.ridge, "With --fit-wiener-bank: the ridge, of the mean diagonal")->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--validate", bank_validate,
                 "With --fit-wiener-bank: score the fitted bank on clips FIRST..LAST (validation: 1001..1300) instead "
                 "of printing it");
  app.add_option("--oracle-fir", oracle_range,
                 "Clips FIRST..LAST: each clip's own least-squares causal FIR (an oracle that knows the clip's truth), "
                 "12 taps at delays 0.5, 0.9 and 1 frame, and banks chosen by the drawn tremor or fitted (wiener-bank): "
                 "how close a causal linear filter can come to the ceiling");
  app.add_option("--min-cutoff", min_cutoff, "One Euro min_cutoff_hz to try instead of the default");
  app.add_option("--beta", beta, "One Euro beta to try instead of the default");
  app.add_option("--d-cutoff", d_cutoff, "One Euro d_cutoff_hz to try instead of the default");
  bool per_frame = false;
  app.add_flag("--per-frame", per_frame, "Also print each scored frame's error");
  app.add_option("--max-speed", max_speed, "Score frames whose intended speed is below this (m/s): the stroke")
      ->capture_default_str();
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::filter::SmootherParams defaults;
  tachi::filter::OneEuroParams chosen = defaults.one_euro;
  if (min_cutoff > 0) chosen.min_cutoff_hz = min_cutoff;
  if (beta >= 0) chosen.beta = beta;
  if (d_cutoff > 0) chosen.d_cutoff_hz = d_cutoff;
  if (lag_compensation >= 0) chosen.lag_compensation = lag_compensation;
  if (!fit_range.empty()) return fit_wiener(parse_range(fit_range), taps, delay);
  if (!tune_range.empty()) return tune(parse_range(tune_range));
  if (!oracle_range.empty()) return oracle_fir(parse_range(oracle_range));
  if (!bank_range.empty()) {
    using W = tachi::filter::WienerBankFit::Weighting;
    if (app.count("--delay") > 0) bank_fit.delay = delay;
    bank_fit.weighting = bank_weighting == "pooled" ? W::Pooled : bank_weighting == "ceiling" ? W::Ceiling : W::MeanRatio;
    return fit_wiener_bank(parse_range(bank_range), bank_fit, bank_validate);
  }
  if (!tremor_range.empty()) return tremor_table(parse_range(tremor_range), chosen);
  if (truth_csv.empty()) throw std::invalid_argument("--truth is needed (or --tremor, --tune, --fit-wiener, --fit-wiener-bank, --oracle-fir)");

  const Truth truth = read_truth(truth_csv);
  std::vector<HandSample> hands;
  if (!hands_csv.empty()) {
    std::ifstream in(hands_csv);
    hands = tachi::filter::read_hand_csv(in).samples;
  } else {
    for (const auto& [frame, p] : truth.palm) {
      HandSample h;
      h.frame = frame;
      h.stamp_ns = static_cast<std::int64_t>(frame) * 33'333'333;
      h.position_m = p.cast<float>();
      h.tracked = truth.visible.at(frame);
      hands.push_back(h);
    }
  }

  tachi::filter::SmootherParams base;
  if (min_cutoff > 0) base.one_euro.min_cutoff_hz = min_cutoff;
  if (beta >= 0) base.one_euro.beta = beta;
  if (d_cutoff > 0) base.one_euro.d_cutoff_hz = d_cutoff;
  if (lag_compensation >= 0) base.one_euro.lag_compensation = lag_compensation;
  std::vector<std::pair<std::string, tachi::filter::SmootherParams>> variants;
  auto raw = base;
  raw.kind = tachi::filter::SmootherKind::None;
  variants.emplace_back("raw", raw);
  for (std::size_t n : {3U, 5U, 9U}) {
    auto ma = base;
    ma.kind = tachi::filter::SmootherKind::MovingAverage;
    ma.moving_average_window = n;
    variants.emplace_back("moving average N=" + std::to_string(n), ma);
  }
  const auto add_euro = [&](tachi::filter::OneEuroParams params, const char* what) {
    auto euro = base;
    euro.kind = tachi::filter::SmootherKind::OneEuro;
    euro.one_euro = params;
    char name[160];
    std::snprintf(name, sizeof name, "One Euro %s (%.1f Hz, beta %.1f, comp %.0f)", what, params.min_cutoff_hz, params.beta,
                  params.lag_compensation);
    variants.emplace_back(name, euro);
  };
  add_euro(base.one_euro, "default");
  {
    auto wiener = base;
    wiener.kind = tachi::filter::SmootherKind::Wiener;
    variants.emplace_back("wiener (12 taps, seeds 1..1000)", wiener);
    auto bank = base;
    bank.kind = tachi::filter::SmootherKind::WienerBank;
    variants.emplace_back("wiener-bank (5^3 bins, seeds 1..1000)", bank);
  }
  // The paper's filter at the settings its tuning procedure starts from (1 Hz, beta 0 -> 3), and the
  // optional lag compensation (not in the paper) at the former default.
  add_euro({1.0, 3.0, 1.0, 0.0}, "paper, 1 Hz");
  add_euro({1.0, 3.0, 1.0, 1.0}, "lag-compensated option");
  std::printf("input: %s, %zu samples\n", hands_csv.empty() ? "ground-truth palm (tremor, no sensor error)" : hands_csv.c_str(),
              hands.size());
  std::printf("%-52s %10s %8s %10s %14s %16s\n", "smoother", "rms_mm", "vs_raw", "lag_fr", "rms@lag_mm", "frames_scored");
  double raw_rms = 0;
  for (const auto& [label, p] : variants) {
    const auto out = run(hands, truth, p, max_speed);
    const Score s = score(truth, out);
    if (per_frame) {
      for (const auto& [frame, q] : out) std::printf("  %s frame %llu err %.1f\n", label.c_str(), static_cast<unsigned long long>(frame), (q - truth.intended.at(frame)).norm() * 1000);
    }
    if (p.kind == tachi::filter::SmootherKind::None) raw_rms = s.rms_mm;
    std::printf("%-52s %10.2f %8.2f %10.2f %14.2f %16zu\n", label.c_str(), s.rms_mm, s.rms_mm / raw_rms, s.lag_frames,
                s.rms_at_lag_mm, out.size());
  }
  return 0;
} catch (const std::exception& e) {
  std::cerr << "tachi-filter-bench: " << e.what() << '\n';
  return 1;
}
