#include "tachi/sim/cut_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace tachi::sim {

std::vector<GridCoord> rasterise_segment(GridCoord a, GridCoord b) {
  if (a == b) return {a};
  if (b.u < a.u) {
    // Right to left: the same particles as left to right, so a stroke and its reverse cut alike.
    auto out = rasterise_segment(b, a);
    std::reverse(out.begin(), out.end());
    return out;
  }
  std::vector<GridCoord> out;
  out.reserve(static_cast<std::size_t>(std::abs(b.u - a.u) + std::abs(b.v - a.v) + 1));
  out.push_back(a);
  if (a.u == b.u) {
    // Vertical: eq. (2) has no slope; the line is the column between the two particles.
    const int step = b.v > a.v ? 1 : -1;
    for (int v = a.v + step; v != b.v + step; v += step) out.push_back({a.u, v});
    return out;
  }
  // Eqs. (1)-(4) in integers: v = a (u_k - u_i) - sum v_n is N / du with N = dv (u_k - u_i) - sum du,
  // and C++ division truncates towards zero, which is exactly eq. (4). At u_k = u_j it is exact, so the
  // line ends on P_j.
  const int du = b.u - a.u;
  const int dv = b.v - a.v;
  int sum = 0;  // sum of v_n so far: rows already descended (or climbed) since P_i
  for (int k = 1; k <= du; ++k) {
    const int u = a.u + k;
    out.push_back({u, a.v + sum});
    const long long n = static_cast<long long>(dv) * k - static_cast<long long>(sum) * du;
    const int vk = static_cast<int>(n / du);
    const int step = vk > 0 ? 1 : -1;
    for (int i = 1; i <= std::abs(vk); ++i) out.push_back({u, a.v + sum + step * i});
    sum += vk;
  }
  return out;
}

namespace {

/// Index of the first particle from which the line leaves the boundary (the start of its first edge
/// that is not a boundary edge), or the last index when every edge runs along the boundary.
std::size_t leading_boundary_run(std::span<const GridCoord> line, int columns, int rows) {
  std::size_t i = 0;
  while (i + 1 < line.size() && boundary_edge(line[i], line[i + 1], columns, rows)) ++i;
  return i;
}

}  // namespace

std::vector<GridCoord> CutLineBuilder::append(GridCoord g) {
  g.u = std::clamp(g.u, 0, columns_ - 1);
  g.v = std::clamp(g.v, 0, rows_ - 1);
  if (line_.empty()) {
    line_.push_back(g);
    return {g};
  }
  const GridCoord start = line_.back();
  if (g == start) return {};
  const std::size_t old_size = line_.size();
  GridCoord from = start;
  if (old_size == 1 && rows_ > 2) {
    // Seed 000 Figure 2 (b): a cut starting at the top (bottom) edge first steps one row in, or the
    // column-first rasterisation would run along the edge.
    const bool top = start.v == 0;
    const bool bottom = start.v == rows_ - 1;
    const GridCoord inward{start.u, top ? 1 : rows_ - 2};
    const bool already_inward = g.u == start.u;  // a vertical segment enters by itself
    if ((top || bottom) && !already_inward) {
      line_.push_back(inward);
      from = inward;
    }
  }
  if (!(g == from)) {
    const auto seg = rasterise_segment(from, g);
    line_.insert(line_.end(), seg.begin() + 1, seg.end());
  }
  // A line that so far only followed the edge cut nothing: restart it where it leaves the edge.
  const std::size_t drop = leading_boundary_run(line_, columns_, rows_);
  line_.erase(line_.begin(), line_.begin() + static_cast<std::ptrdiff_t>(drop));
  const std::size_t first_new = old_size - 1 >= drop ? old_size - 1 - drop : 0;
  return {line_.begin() + static_cast<std::ptrdiff_t>(first_new), line_.end()};
}

const std::vector<GridCoord>& CutLineBuilder::finish() {
  std::size_t end = line_.size();
  while (end >= 2 && boundary_edge(line_[end - 2], line_[end - 1], columns_, rows_)) --end;
  line_.resize(end);
  return line_;
}

void CutLineBuilder::drop_last(std::size_t count) { line_.resize(line_.size() - std::min(count, line_.size())); }

std::vector<GridCoord> build_cut_line(std::span<const GridCoord> points, int columns, int rows) {
  CutLineBuilder builder{columns, rows};
  for (const GridCoord g : points) builder.append(g);
  return builder.finish();
}

float cut_line_length(std::span<const GridCoord> line, float spacing_x, float spacing_y) {
  float length = 0.0F;
  for (std::size_t i = 1; i < line.size(); ++i) {
    const float dx = static_cast<float>(line[i].u - line[i - 1].u) * spacing_x;
    const float dy = static_cast<float>(line[i].v - line[i - 1].v) * spacing_y;
    length += std::sqrt(dx * dx + dy * dy);
  }
  return length;
}

std::optional<std::pair<double, double>> clip_to_rectangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                                            double max_u, double max_v) {
  double t0 = 0.0;
  double t1 = 1.0;
  const Eigen::Vector2d d = b - a;
  const std::array<double, 4> p{-d.x(), d.x(), -d.y(), d.y()};
  const std::array<double, 4> q{a.x(), max_u - a.x(), a.y(), max_v - a.y()};
  for (std::size_t i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return std::nullopt;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0.0) {
      t0 = std::max(t0, r);
    } else {
      t1 = std::min(t1, r);
    }
  }
  if (t0 > t1) return std::nullopt;
  return std::pair{t0, t1};
}

}  // namespace tachi::sim
