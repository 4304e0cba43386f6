// An exact cut's tips where the blade entered and left the cloth, through the path a user's stroke takes: the
// Session (the blade's contact, BladeContact, in front of the StrokeCutter), as tachi-sim --offline --stroke
// runs it (docs/cutting.md, section 8, "Tips").
#include "tachi/sim/session.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace tachi::sim {
namespace {

/// The ends of the cuts in rest coordinates (cells): the particles on a cut's lips (edges of one live triangle,
/// not both on the cloth's rim) that have no copy at their rest coordinate, where a slit's two lips meet.
std::vector<Eigen::Vector2d> cut_tips(const Cloth& cloth) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    for (std::size_t e = 0; e < 3; ++e) {
      const std::uint32_t a = tri[e];
      const std::uint32_t b = tri[(e + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  const auto on_rim = [&](std::uint32_t i) {
    const Eigen::Vector2f p = cloth.rest_uv[i];
    return p.x() <= 1e-5F || p.y() <= 1e-5F || p.x() >= static_cast<float>(cloth.columns - 1) - 1e-5F ||
           p.y() >= static_cast<float>(cloth.rows - 1) - 1e-5F;
  };
  std::set<std::uint32_t> lips;
  for (const auto& [edge, count] : edges) {
    if (count != 1 || (on_rim(edge.first) && on_rim(edge.second))) continue;
    lips.insert(edge.first);
    lips.insert(edge.second);
  }
  std::vector<Eigen::Vector2d> tips;
  for (const std::uint32_t i : lips) {
    const bool copied = std::any_of(lips.begin(), lips.end(), [&](std::uint32_t j) {
      return j != i && (cloth.rest_uv[j] - cloth.rest_uv[i]).norm() < 1e-4F;
    });
    if (!copied) tips.push_back(cloth.rest_uv[i].cast<double>());
  }
  return tips;
}

double nearest(const std::vector<Eigen::Vector2d>& tips, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& q : tips) best = std::min(best, (q - p).norm());
  return best;
}

/// World point over the material point (u, v) of the cloth as it is: bilinear in its grid particles'
/// positions, `front_m` in front (+z, towards the camera).
Eigen::Vector3f over(const Cloth& cloth, const Eigen::Vector2d& uv, float front_m) {
  const int u0 = std::clamp(static_cast<int>(std::floor(uv.x())), 0, cloth.columns - 2);
  const int v0 = std::clamp(static_cast<int>(std::floor(uv.y())), 0, cloth.rows - 2);
  const auto fu = static_cast<float>(uv.x() - u0);
  const auto fv = static_cast<float>(uv.y() - v0);
  const auto at = [&](int u, int v) { return cloth.position[static_cast<std::size_t>(v * cloth.columns + u)]; };
  const Eigen::Vector3f p = (1 - fu) * (1 - fv) * at(u0, v0) + fu * (1 - fv) * at(u0 + 1, v0) +
                            (1 - fu) * fv * at(u0, v0 + 1) + fu * fv * at(u0 + 1, v0 + 1);
  return p + Eigen::Vector3f{0.0F, 0.0F, front_m};
}

struct Tips {
  std::vector<double> entry, exit;
  int not_a_slit = 0;  // strokes whose cut did not end in two tips
};

/// Random slits drawn on a 64 x 64 top-pinned cloth hanging at rest: a quadratic Bezier between two points
/// 3 cells or more inside the cloth and 8 or more apart, bowed by up to a quarter of its length, 1-2 cm in
/// front, at 0.2-2 m/s and 60 Hz, one sample per step. Each sample is over the material point of the path on
/// the cloth as it hung before the stroke; the tips are compared with the path's first and last points.
Tips measure(Blade blade, int strokes, std::uint32_t seed) {
  constexpr int n = 64;
  Tips out;
  std::mt19937 rng{seed};
  std::uniform_real_distribution<double> unit{0.0, 1.0};
  for (int k = 0; k < strokes; ++k) {
    SessionOptions options;
    options.cloth.columns = options.cloth.rows = n;
    options.cloth.pin = PinMode::TopEdge;
    options.stroke.mode = CutMode::Exact;
    options.stroke.blade = blade;
    Session session{options};
    for (int s = 0; s < 60; ++s) session.step();
    const auto in = [&] { return 3.0 + (n - 7.0) * unit(rng); };
    const Eigen::Vector2d a{in(), in()};
    Eigen::Vector2d b{in(), in()};
    if ((b - a).norm() < 8.0) b = a + 8.0 * (b - a).normalized();
    b = b.cwiseMax(3.0).cwiseMin(n - 4.0);
    const Eigen::Vector2d mid = 0.5 * (a + b) + (unit(rng) - 0.5) * 0.5 * Eigen::Vector2d{-(b - a).y(), (b - a).x()};
    const auto front = static_cast<float>(0.01 + 0.01 * unit(rng));
    const double speed_cells = (0.2 + 1.8 * unit(rng)) * (n - 1) / 60.0;  // cells per sample
    const int samples = std::max(2, static_cast<int>(std::ceil((b - a).norm() * 1.1 / speed_cells)));
    const Cloth hanging = session.cloth();
    for (int i = 0; i <= samples; ++i) {
      const double s = static_cast<double>(i) / samples;
      const Eigen::Vector2d uv = (1 - s) * (1 - s) * a + 2 * (1 - s) * s * mid + s * s * b;
      session.on_hand({1, 1.0 + i / 60.0, over(hanging, uv, front), true, true});
      session.step();
    }
    session.end_stroke();
    const auto tips = cut_tips(session.cloth());
    if (tips.size() != 2) {
      ++out.not_a_slit;
      continue;
    }
    out.entry.push_back(nearest(tips, a));
    out.exit.push_back(nearest(tips, b));
  }
  return out;
}

double median(std::vector<double> x) {
  if (x.empty()) return 0.0;
  std::sort(x.begin(), x.end());
  return x[x.size() / 2];
}

double largest(const std::vector<double>& x) { return x.empty() ? 0.0 : *std::max_element(x.begin(), x.end()); }

// The blade drags the cloth from the sample that meets it until it is through (one sample for a sharp blade, many
// for a worn one). The cut began at the approach sample located on the dragged cloth, behind the point the blade
// met by as far as it dragged the cloth: 0.36 cell at the median, up to 4.9 (scalpel) and 10 (worn) over these
// strokes. Now it begins where the blade met the cloth, located when it met it; the exit tip is the last
// sample's point, within the exact cut's snap distance (0.08 cell) of it.
TEST(CutTips, AnExactCutEndsWhereTheStrokeEndsAtBothTips) {
  for (const Blade blade : {Blade::Scalpel, Blade::Worn}) {
    SCOPED_TRACE(std::string{to_string(blade)});
    constexpr int kStrokes = 50;
    const Tips tips = measure(blade, kStrokes, 5);
    std::printf("%s: entry median %.3f max %.3f, exit median %.3f max %.3f cells; %d of %d strokes not one slit\n",
                std::string{to_string(blade)}.c_str(), median(tips.entry), largest(tips.entry), median(tips.exit),
                largest(tips.exit), tips.not_a_slit, kStrokes);
    // A worn blade moving slowly never gets through (it drags the cloth): no slit to measure.
    EXPECT_GE(tips.entry.size(), kStrokes * 9U / 10U);
    EXPECT_LE(largest(tips.entry), 0.1);
    EXPECT_LE(largest(tips.exit), 0.1);
  }
}

}  // namespace
}  // namespace tachi::sim
