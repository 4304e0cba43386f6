// Exact cutting: the cut follows the blade's own path across the cloth instead of the grid lines that seed
// 000 (section 3.2: "along a grid line of the cloth model for simplicity") and seed 001 (whole triangles)
// settle for. A segment of the path, in rest (material) coordinates, is cut in four steps:
//  1. its end points that fall inside a triangle, away from its edges, become particles (the triangle is
//     split in three), so a slit ends where the stroke ends;
//  2. every particle within `snap` of the segment is ON the cut (it snaps); every triangle edge whose two
//     ends lie strictly on opposite sides of the segment, and that the segment crosses, gets a new particle
//     at the crossing (position, velocity and rest coordinate interpolated; its mass is taken from the
//     edge's ends by the lumped-area rule below, so mass is conserved);
//  3. each triangle with new particles on its edges is split so that the piece of the path inside it is one
//     of its edges (a corner triangle and a quad cut by its shorter diagonal);
//  4. the triangle fans around the particles on the path are split into the groups that stay connected
//     across edges that are not cut, each group but one getting its own copy (as ClothCutter does for the
//     grid), then structural and shear springs are re-derived locally from the triangles' edges (rest
//     lengths from rest coordinates), and bend springs that cross or touch the path are removed (seed 001:
//     a bend goes with the structural springs it spans).
// Guarantees (docs/cutting.md): every cut edge lies within `snap` of the segment (0.08 cells); a new
// particle on an edge is at least snap / (edge length) of the edge from either end, i.e. no split makes
// an edge piece shorter than 0.08 / 1.42 = 5.7 % of the edge it splits (diagonals) or 8 % (grid edges).
// Lumped mass (as for linear finite elements): a particle's mass is shared equally by its triangles;
// splitting a triangle moves to the new particle the part of each corner's share that the corner loses in
// area, so vertex a gives barycentric(a at the new point) times its share.
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/union_find.hpp"
#include "tachi/sim/cutting.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace tachi::sim {

/// Distance under which a particle is taken to lie on the cut, in grid cells.
inline constexpr double kExactSnapCells = 0.08;

/// Whether p and x are the far corners of two live triangles sharing an edge: the grid's second diagonal
/// of a cell (a shear spring that is no triangle edge) stays while its cell's two triangles do.
[[nodiscard]] bool across_quad(const Cloth& cloth, std::uint32_t p, std::uint32_t x);

/// Cuts one cloth along segments in rest coordinates. Keeps which triangles lie in which grid cell, so it
/// must see every topology change of its cloth (no other cutter may cut the same cloth).
class ExactCutter {
 public:
  explicit ExactCutter(Cloth& cloth, double snap_cells = kExactSnapCells);

  /// Cuts along the segment from `from` to `to` (rest coordinates in cells: u right, v down, the uncut
  /// grid particle (u, v) at (u, v)). Parts outside the cloth or over holes cut nothing.
  TopologyChange cut(const Eigen::Vector2d& from, const Eigen::Vector2d& to);

  /// Seed 001's cut (section 4, "mesh triangle deletion"), for comparison: the mesh edges the segment
  /// crosses lose their springs; a triangle with two such edges is deleted and the particle between them
  /// is completeCUT (it loses its structural and shear springs and every triangle it is in); a particle
  /// left in no triangle loses every spring, and so does a spring no triangle borders. No particle is made.
  TopologyChange remove_crossed(const Eigen::Vector2d& from, const Eigen::Vector2d& to);

  /// Largest distance of a cut edge from the segment that made it, in cells (0 before any cut).
  [[nodiscard]] double max_deviation_cells() const { return max_deviation_; }
  /// The cut edges made so far, as rest-coordinate segments (cells), in the order they were made.
  [[nodiscard]] const std::vector<std::array<Eigen::Vector2f, 2>>& cut_edges() const { return cut_edges_; }
  /// Total rest length of the cut edges, metres.
  [[nodiscard]] double cut_length_m() const { return cut_length_m_; }
  [[nodiscard]] double snap_cells() const { return snap_; }

 private:
  struct Split {
    std::uint32_t a;  // a < b
    std::uint32_t b;
    double t;         // from a
    std::uint32_t particle;
    std::uint32_t next;  // the next split of this cut whose `a` is the same particle (kNone: the last)
  };
  /// Fills the change's "before" fields; the segment clipped to the cloth, or nothing to cut.
  std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> begin(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                                                                   TopologyChange& change) const;
  void grow_particle_scratch();
  void register_triangle(std::uint32_t t);
  void unregister_triangle(std::uint32_t t);
  [[nodiscard]] std::size_t cell_of(std::uint32_t t) const;
  void gather(const Eigen::Vector2d& from, const Eigen::Vector2d& to);
  void finish(TopologyChange& change, std::uint32_t version_before);
  void insert_point(const Eigen::Vector2d& p, TopologyChange& change);
  std::uint32_t replace_triangle(std::uint32_t t, std::array<std::uint32_t, 3> vertices, TopologyChange& change);
  [[nodiscard]] const Split* split_on(std::uint32_t a, std::uint32_t b) const;
  void separate(std::uint32_t c, TopologyChange& change);
  void remove_triangle(std::uint32_t t, TopologyChange& change);
  void rederive_springs(std::uint32_t p, TopologyChange& change);
  void add_bends(std::uint32_t p, TopologyChange& change);
  /// Adds p to touched_particles_, once per cut (a stamp instead of sorting out ~6 repeats of each).
  void touch(std::uint32_t p) {
    if (p >= touched_stamp_.size()) touched_stamp_.resize(cloth_->particle_count() + 64, 0);
    if (touched_stamp_[p] == stamp_) return;
    touched_stamp_[p] = stamp_;
    touched_particles_.push_back(p);
  }
  /// Whether a-b is a cut edge. Inline: it runs for every edge add_bends and separate look at, and almost
  /// every particle has no cut edge (on_a_cut_, one byte a particle, answers that without the lists).
  [[nodiscard]] bool is_cut(std::uint32_t a, std::uint32_t b) const {
    return a < on_a_cut_.size() && on_a_cut_[a] != 0 && cut_partners_[a].contains(b);
  }
  void mark_cut(std::uint32_t a, std::uint32_t b);
  std::uint32_t particle_on_edge(std::uint32_t a, std::uint32_t b, double t, TopologyChange& change);
  void split_edge_at(std::uint32_t a, std::uint32_t b, double t, TopologyChange& change);
  [[nodiscard]] Eigen::Vector2d uv(std::uint32_t p) const { return cloth_->rest_uv[p].cast<double>(); }

  Cloth* cloth_;
  double snap_;
  int cell_columns_;
  int cell_rows_;
  std::vector<std::vector<std::uint32_t>> cell_triangles_;  // per cell (v * (columns - 1) + u): live triangles
  std::vector<std::uint32_t> triangle_cell_;
  // Per particle: the particles it has a cut edge to (inline lists: a particle on a cut has two, four where
  // cuts cross; std::vector here cost three allocations per new cut edge).
  std::vector<SmallIndexList<4>> cut_partners_;
  std::vector<std::uint8_t> on_a_cut_;  // per particle: 1 when its cut_partners_ list is not empty
  // Scratch of one cut. A stamp marks what this cut has seen: an entry equal to stamp_ is this cut's.
  std::vector<std::uint32_t> triangle_stamp_;
  std::vector<std::uint32_t> particle_stamp_;
  std::vector<std::uint32_t> cell_stamp_;    // gather: the cell's triangles are candidates already
  std::vector<std::uint32_t> spring_stamp_;  // a shear spring kept across a quad, a bend tested against the path
  std::vector<std::uint32_t> edge_stamp_;    // add_bends: per triangle, whether edge_visited_ is this cut's
  std::vector<std::uint8_t> edge_visited_;   // add_bends: per triangle, bit e = its edge e was visited
  std::uint32_t stamp_ = 0;
  std::vector<std::uint32_t> candidates_;
  std::vector<Split> splits_;
  std::vector<std::uint32_t> split_head_;  // per particle stamped this cut: its first split as `a`, or kNone
  std::vector<std::array<std::uint32_t, 2>> cut_pairs_;
  std::vector<std::uint32_t> touched_particles_;  // each once (touched_stamp_), sorted before use
  std::vector<std::uint32_t> touched_stamp_;
  std::vector<double> side_;            // per particle: signed distance from the segment's line, cells
  std::vector<std::uint8_t> snapped_;   // per particle: within snap of the segment
  std::vector<std::uint32_t> neighbourhood_;
  std::vector<std::uint32_t> bends_;
  std::vector<std::uint32_t> doomed_;  // springs to remove once the list they are in has been read
  std::vector<std::uint32_t> wanted_;
  std::vector<std::uint64_t> opposite_edges_;  // rederive_springs: p's triangles' edges opposite p, as keys
  // rederive_springs: per particle, wanted_mark_ when p wants a spring to it, + 1 once that spring is found.
  std::vector<std::uint32_t> wanted_marks_;
  std::uint32_t wanted_mark_ = 0;
  struct CutEdge {  // a cut edge of this segment in rest coordinates, for the bend-removal tests
    Eigen::Vector2d x;
    Eigen::Vector2d y;
    Eigen::Vector2d lo;  // its box: min and max of x and y
    Eigen::Vector2d hi;
  };
  std::vector<CutEdge> cut_edges_uv_;
  std::vector<std::uint32_t> on_cut_;
  std::vector<std::uint32_t> fan_;  // separate: the triangles around the particle
  UnionFind<std::size_t> fan_groups_;
  std::vector<std::size_t> fan_roots_;
  std::vector<std::uint32_t> partners_;
  // Results.
  double max_deviation_ = 0.0;
  double cut_length_m_ = 0.0;
  std::vector<std::array<Eigen::Vector2f, 2>> cut_edges_;
};

}  // namespace tachi::sim
