// The cut line: the chain of grid particles a cut runs through, every consecutive pair joined by a
// structural spring, so the cut follows grid lines (seed 000 section 3: "a cut line is made along a grid
// line of the cloth model for simplicity"). Pure grid arithmetic, no cloth needed.
//
// Between two chosen particles the line is the slope rasterisation of eqs. (1)-(4) of Mesuda et al.
// (seed 000 section 3.2): step one column towards P_j, then the accumulated vertical offset rounded
// towards zero in that column. What the paper leaves open is decided here: right-to-left pairs are
// rasterised left-to-right and reversed (so a segment gives the same particles in either direction),
// vertical pairs are a straight run, repeated particles add nothing. The top/bottom extra-particle rule
// (Figure 2 (b)) and a trim of the runs that only follow the boundary keep a cut from sliding along an
// edge where it separates nothing (Figures 6-7).
#pragma once

#include "tachi/sim/cloth.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace tachi::sim {

/// True when a and b are 4-neighbours (one structural spring apart).
[[nodiscard]] constexpr bool grid_adjacent(GridCoord a, GridCoord b) {
  const int du = a.u - b.u;
  const int dv = a.v - b.v;
  return (du == 0 && (dv == 1 || dv == -1)) || (dv == 0 && (du == 1 || du == -1));
}

[[nodiscard]] constexpr bool on_boundary(GridCoord g, int columns, int rows) {
  return g.u == 0 || g.v == 0 || g.u == columns - 1 || g.v == rows - 1;
}

/// True when the structural edge a-b lies along the grid's boundary (it belongs to one cell only,
/// so cutting it separates nothing).
[[nodiscard]] constexpr bool boundary_edge(GridCoord a, GridCoord b, int columns, int rows) {
  return (a.u == b.u && (a.u == 0 || a.u == columns - 1)) || (a.v == b.v && (a.v == 0 || a.v == rows - 1));
}

/// Cut line from P_i to P_j, both included: eqs. (1)-(4) of Mesuda et al. (seed 000 section 3.2).
/// Every consecutive pair of the result is grid_adjacent; a == b gives {a}.
[[nodiscard]] std::vector<GridCoord> rasterise_segment(GridCoord a, GridCoord b);

/// Grows a cut line point by point (one call per chosen particle, as the hand moves), applying the
/// paper's start rule and dropping repeats. Each call returns only the particles it added, so a caller
/// can cut progressively; line() is the whole line so far.
class CutLineBuilder {
 public:
  CutLineBuilder(int columns, int rows) : columns_(columns), rows_(rows) {}

  /// Appends the particle at g (clamped to the grid). Returns the particles added to the line, starting
  /// with the previous last particle when there was one (so consecutive pairs are the new cut edges).
  /// The first point of a line on the top (bottom) edge is followed by (u, 1) ((u, rows - 2)), as in
  /// seed 000 section 3.2, so the line enters the cloth instead of following its edge; while the line
  /// so far only runs along the boundary it is shortened to its last particle (it has cut nothing yet).
  std::vector<GridCoord> append(GridCoord g);

  /// Ends the line: drops a trailing run along the boundary (the cut already reached the edge where
  /// the run began). Returns the final line.
  const std::vector<GridCoord>& finish();

  /// Drops the line's last `count` particles (the caller ends the line earlier than its last append went).
  void drop_last(std::size_t count);

  [[nodiscard]] const std::vector<GridCoord>& line() const { return line_; }
  [[nodiscard]] bool empty() const { return line_.empty(); }

 private:
  int columns_;
  int rows_;
  std::vector<GridCoord> line_;
};

/// Whole-line convenience: every point appended to a CutLineBuilder in order, then finish().
[[nodiscard]] std::vector<GridCoord> build_cut_line(std::span<const GridCoord> points, int columns, int rows);

/// Liang-Barsky: the part [t0, t1] of the segment a + t (b - a), t in [0, 1], inside the rectangle
/// [0, max_u] x [0, max_v]; nothing when the segment misses it.
[[nodiscard]] std::optional<std::pair<double, double>> clip_to_rectangle(const Eigen::Vector2d& a,
                                                                         const Eigen::Vector2d& b, double max_u,
                                                                         double max_v);

/// Length of a cut line in rest metres (sum of the structural rest lengths it runs along).
[[nodiscard]] float cut_line_length(std::span<const GridCoord> line, float spacing_x, float spacing_y);

}  // namespace tachi::sim
