#include "tachi/sim/cut_stability.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <fstream>
#include <random>
#include <stdexcept>

namespace tachi::sim {

std::vector<StrokeSample> random_stroke(std::uint64_t seed) {
  std::mt19937_64 rng{seed};
  std::uniform_real_distribution<double> unit{0.0, 1.0};
  const auto in = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  // Two end points at least 0.3 m apart, a control point that bends the path by up to a third of its length.
  Eigen::Vector2d a;
  Eigen::Vector2d b;
  do {
    a = {in(-0.7, 0.7), in(-0.45, 0.45)};
    b = {in(-0.7, 0.7), in(-0.45, 0.45)};
  } while ((b - a).norm() < 0.3);
  const Eigen::Vector2d normal = Eigen::Vector2d{-(b - a).y(), (b - a).x()};
  const bool curved = unit(rng) < 0.5;
  const Eigen::Vector2d control = 0.5 * (a + b) + (curved ? in(-1.0 / 3.0, 1.0 / 3.0) : 0.0) * normal;
  const double z = in(0.0, 0.03);
  const double speed = in(0.2, 2.0);
  const double length = (b - a).norm() * (curved ? 1.2 : 1.0);
  const int n = std::max(2, static_cast<int>(std::ceil(length / speed * 60.0)));
  std::vector<StrokeSample> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) {
    const double s = static_cast<double>(i) / n;
    const Eigen::Vector2d p = (1 - s) * (1 - s) * a + 2 * (1 - s) * s * control + s * s * b;
    out.push_back({0.3 + i / 60.0, Eigen::Vector3d{p.x(), p.y(), z}.cast<float>()});
  }
  return out;
}

std::vector<StrokeSample> perturbed(const std::vector<StrokeSample>& stroke, double metres, std::uint64_t seed) {
  std::mt19937_64 rng{seed};
  std::normal_distribution<double> gauss{0.0, 1.0};
  std::vector<StrokeSample> out = stroke;
  for (StrokeSample& s : out) {
    Eigen::Vector3d d{gauss(rng), gauss(rng), gauss(rng)};
    d *= metres / std::max(d.norm(), 1e-12);
    s.position = (s.position.cast<double>() + d).cast<float>();
  }
  return out;
}

std::vector<StrokeSample> there_back_and_there(const std::vector<StrokeSample>& stroke) {
  std::vector<StrokeSample> out = stroke;
  if (stroke.size() < 2) return out;
  const double step = stroke[1].t - stroke[0].t;
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t n = stroke.size();
    for (std::size_t k = 1; k < n; ++k) {
      const std::size_t i = pass == 0 ? n - 1 - k : k;
      out.push_back({out.back().t + step, stroke[i].position});
    }
  }
  return out;
}

void write_stroke_csv(const std::vector<StrokeSample>& stroke, const std::filesystem::path& file) {
  std::ofstream out{file};
  out << "t,x,y,z\n";
  char row[128];
  for (const StrokeSample& s : stroke) {
    std::snprintf(row, sizeof row, "%.17g,%.9g,%.9g,%.9g\n", s.t, static_cast<double>(s.position.x()),
                  static_cast<double>(s.position.y()), static_cast<double>(s.position.z()));
    out << row;
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

int offline_steps(const std::vector<StrokeSample>& stroke) {
  return stroke.empty() ? 0 : static_cast<int>(std::ceil((stroke.back().t + 0.5) * 60.0));
}

CutOutcome cut_outcome(const std::vector<StrokeSample>& stroke, Blade blade, CutMode mode, int grid,
                       const std::filesystem::path& scratch) {
  write_stroke_csv(stroke, scratch);
  OfflineOptions o;
  o.cloth.columns = o.cloth.rows = grid;
  o.cloth.pin = PinMode::TopEdge;
  o.blade = blade;
  o.cut_mode = mode;
  o.stroke_file = scratch;
  o.steps = offline_steps(stroke);
  const Summary s = run_offline(o);
  return {s.pieces, s.extra.at("cut_length_m").get<double>(), s.extra.at("stroke_outliers").get<std::size_t>()};
}

namespace {

/// 60 Hz samples from (x0, y) to (x1, y), 2 cm in front of the cloth, over `seconds` from t = 0.5 s.
std::vector<StrokeSample> straight_stroke(double x0, double x1, double y, double seconds) {
  const int n = static_cast<int>(std::lround(seconds * 60.0));
  std::vector<StrokeSample> out;
  for (int i = 0; i <= n; ++i) {
    const double a = static_cast<double>(i) / n;
    out.push_back({0.5 + seconds * a, Eigen::Vector3d{x0 + (x1 - x0) * a, y, 0.02}.cast<float>()});
  }
  return out;
}

}  // namespace

std::string blade_table(const std::filesystem::path& scratch) {
  const std::vector<StrokeSample> strokes[] = {straight_stroke(-0.7, 0.7, 0.0, 6.0), straight_stroke(-0.7, 0.7, 0.0, 2.0),
                                               straight_stroke(-0.1, 0.1, -0.45, 6.0)};
  const Blade blades[] = {Blade::Razor, Blade::Scalpel, Blade::Utility, Blade::Kitchen, Blade::Hunting, Blade::Worn};
  std::string out =
      "| blade (force) | 6 s across: cut m / drag mm / pieces | 2 s across: cut m / drag mm / pieces | slow push on "
      "the free flap: cut m / drag mm / pieces |\n|---|---|---|---|\n";
  char cell[96];
  for (const Blade blade : blades) {
    std::snprintf(cell, sizeof cell, "| %s (%.3g N) |", std::string{to_string(blade)}.c_str(),
                  static_cast<double>(sharpness(blade).force_n()));
    out += cell;
    for (const auto& stroke : strokes) {
      write_stroke_csv(stroke, scratch);
      OfflineOptions o;
      o.cloth.columns = o.cloth.rows = 64;
      o.cloth.pin = PinMode::TopEdge;
      o.blade = blade;
      o.cut_mode = CutMode::Grid;
      o.stroke_file = scratch;
      o.steps = 420;
      const Summary s = run_offline(o);
      std::snprintf(cell, sizeof cell, " %.3f / %.1f / %zu |", s.extra.at("cut_length_m").get<double>(),
                    1000.0 * s.extra.at("blade_drag_m").get<double>(), s.pieces);
      out += cell;
    }
    out += "\n";
  }
  return out;
}

}  // namespace tachi::sim
