// Smoothing benchmark on a jittery recording with a known intended path (recordings/jitter: hand tremor
// 6 mm RMS per axis at 4-9 Hz over a slow diagonal cut). For raw, moving average (N = 3, 5, 9) and One Euro
// it prints the RMS 3D error against the intended path, the lag in frames (the shift of the intended path
// that minimises the error, searched in 0.05-frame steps) and the error once that lag is removed.
// Baseline: the raw samples in the same run. See docs/benchmarks.md for the commands and results.
#include "tachi/common/app.hpp"
#include "tachi/filter/hand_csv.hpp"
#include "tachi/filter/smoothing.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

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

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-filter-bench: smoothing error and lag against a recording's intended path"};
  app.name("tachi-filter-bench");
  std::string hands_csv, truth_csv;
  double min_cutoff = -1, beta = -1, d_cutoff = -1, lag_compensation = -1, max_speed = 0.5;
  app.add_option("--lag-compensation", lag_compensation, "One Euro lag_compensation (0 = the paper's filter) to try");
  app.add_option("--hands", hands_csv, "tachi-sensor's CSV for the recording (omit: use the ground-truth palm, tremor only)")
      ->check(CLI::ExistingFile);
  app.add_option("--truth", truth_csv, "The recording's ground_truth.csv (with intended_x,y,z)")->required()->check(CLI::ExistingFile);
  app.add_option("--min-cutoff", min_cutoff, "One Euro min_cutoff_hz to try instead of the default");
  app.add_option("--beta", beta, "One Euro beta to try instead of the default");
  app.add_option("--d-cutoff", d_cutoff, "One Euro d_cutoff_hz to try instead of the default");
  bool per_frame = false;
  app.add_flag("--per-frame", per_frame, "Also print each scored frame's error");
  app.add_option("--max-speed", max_speed, "Score frames whose intended speed is below this (m/s): the stroke")
      ->capture_default_str();
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;

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
