// Topological cutting of the cloth along a cut line (seed 000 section 3.3, seed 001 section 4).
//
// Seed 000 cuts by giving every particle on the cut line a new particle at the same position and
// reconnecting to it the springs on the left side of the two cut vectors v1 (to the previous particle)
// and v2 (to the next one), Figure 3, with a first-particle rule. Seed 001 keeps a triangle mesh
// one-to-one with the particles and deletes what a cut leaves dangling (completeCUT). Done literally, the
// left-side rule breaks where a cut crosses an earlier cut, doubles back, closes on itself or starts
// inside the cloth (the paper's slit-only limitation), so here it decides WHICH side gets the new particle
// while the split itself is made on the triangle fan around the particle:
//  * the fan of triangles around a cut-line particle is split into the groups that stay connected across
//    edges that are not cut; every group but one gets its own duplicate (a boundary particle with one cut
//    edge, an interior one with two or more, a crossing with four); the group on the left of (v1, v2) gets
//    the new particle, as in Figure 3;
//  * structural and shear springs follow the triangles they border (a cut edge ends up with one spring on
//    each side, the paper's "new spring between the new particles"); bend springs whose structural pair is
//    cut or no longer meets at one particle are removed (seed 001: "if the structural spring in a direction
//    is cut, so too is its bend");
//  * completeCUT (seed 001): a particle left without triangles loses its springs, and a spring no triangle
//    borders any more is removed, so nothing bridges the cut.
// Only the particles on the line and their incident springs and triangles are touched (no rebuild).
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/union_find.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace tachi::sim {

/// What one cut changed, relative to the topology version before it (carried by the ClothTopology
/// message: particle particle_count_before + i was duplicated from duplicated_from[i]).
struct TopologyChange {
  std::uint32_t version = 0;                ///< cloth.topology_version after the change
  std::uint32_t particle_count_before = 0;
  std::vector<std::uint32_t> duplicated_from;
  std::vector<std::uint32_t> changed_triangles;  ///< triangles whose vertices changed (sorted, unique)
  std::vector<std::uint32_t> changed_springs;    ///< springs rewired, added or removed (sorted, unique)

  [[nodiscard]] bool empty() const {
    return duplicated_from.empty() && changed_triangles.empty() && changed_springs.empty();
  }
  /// Folds a later change into this one (for one list per stroke).
  void merge(const TopologyChange& later);
};

/// Figure 3 of seed 000: whether the grid direction (du, dv) from a cut-line particle lies on the left
/// of the cut, i.e. strictly inside the sector swept counter-clockwise (seen from +z, v grows downwards)
/// from the vector to the next particle to the vector to the previous one.
[[nodiscard]] bool left_of_cut(GridCoord to_previous, GridCoord to_next, double du, double dv);

/// The 8 grid-neighbour offsets on the left of the cut at a particle (Figure 3): the springs that the
/// paper reconnects to the new particle. At the first (last) particle, pass to_previous = -to_next
/// (to_next = -to_previous): the first-particle rule takes the left of the single cut vector.
[[nodiscard]] std::vector<GridCoord> left_side_neighbours(GridCoord to_previous, GridCoord to_next);

/// Cuts one cloth, incrementally. Keeps which grid edges are cut and which particles share a grid
/// coordinate, so it must see every cut of its cloth (and no one else may duplicate particles).
class ClothCutter {
 public:
  explicit ClothCutter(Cloth& cloth);

  /// Cuts along `line` (consecutive entries 4-neighbours, as CutLineBuilder makes them; other pairs and
  /// coordinates off the grid are skipped). Cutting an already cut edge again changes nothing.
  TopologyChange cut(std::span<const GridCoord> line);

  [[nodiscard]] bool edge_cut(GridCoord a, GridCoord b) const;
  /// Particles sharing the grid coordinate g (the original first).
  [[nodiscard]] std::vector<std::uint32_t> copies(GridCoord g) const;
  /// Takes note of particles someone else appended (the exact cutter), so copies() lists them under the
  /// grid coordinate nearest to them.
  void refresh_copies() { sync_particles(); }
  /// Appends the particles sharing g to `out` (no allocation once `out` has grown).
  void append_copies(GridCoord g, std::vector<std::uint32_t>& out) const;
  [[nodiscard]] const Cloth& cloth() const { return *cloth_; }
  [[nodiscard]] Cloth& cloth() { return *cloth_; }

 private:
  /// Where a structural/shear spring's endpoints sit in the (up to two) cells bordering it, recorded
  /// before the fans are split: after the split, each side's triangle names that side's particles.
  struct SpringAnchor {
    std::uint32_t spring;
    std::array<std::uint32_t, 2> triangle_a;  // per side: a triangle holding endpoint spring_a, or none
    std::array<std::uint32_t, 2> triangle_b;
    std::array<std::uint8_t, 2> slot_a;
    std::array<std::uint8_t, 2> slot_b;
  };
  void sync_particles();
  std::uint8_t* edge_flag(GridCoord a, GridCoord b);
  [[nodiscard]] const std::uint8_t* edge_flag(GridCoord a, GridCoord b) const;
  [[nodiscard]] bool inside(GridCoord g) const {
    return g.u >= 0 && g.v >= 0 && g.u < cloth_->columns && g.v < cloth_->rows;
  }
  void record_anchor(std::uint32_t k);
  void split_fan(std::uint32_t c, GridCoord to_previous, GridCoord to_next, TopologyChange& change);
  void resolve_springs(TopologyChange& change);
  void resolve_bend(std::uint32_t k, TopologyChange& change);
  [[nodiscard]] const std::array<std::uint32_t, 2>* triangles_in_cell(GridCoord cell) const;
  /// The cells on either side of a structural edge (sides = 2), or the one cell of a diagonal (sides = 1).
  static std::array<GridCoord, 2> cells_beside(GridCoord a, GridCoord b, int& sides);
  /// The particles a live triangle along the structural edge a-b holds for a and b.
  [[nodiscard]] std::optional<std::array<std::uint32_t, 2>> edge_particles(GridCoord a, GridCoord b) const;

  Cloth* cloth_;
  std::vector<std::uint8_t> horizontal_cut_;  // edge (u,v)-(u+1,v) at v*(columns-1)+u
  std::vector<std::uint8_t> vertical_cut_;    // edge (u,v)-(u,v+1) at v*columns+u
  std::vector<std::uint32_t> next_copy_;      // per particle: next particle with the same grid coordinate
  std::size_t known_particles_ = 0;
  // Scratch reused between cuts (no allocation in steady state).
  std::vector<std::uint32_t> vertex_stamp_;  // per grid coordinate: stamp_ when on the line being cut
  std::vector<std::uint32_t> vertex_order_;  // per grid coordinate: its place in that line's vertex list
  std::uint32_t stamp_ = 0;
  std::vector<SpringAnchor> anchors_;
  std::vector<std::uint32_t> bends_;
  std::vector<std::array<std::uint32_t, 2>> cell_triangles_;  // per cell (v*(columns-1)+u): its two triangles
  std::vector<std::array<std::uint32_t, 2>> bend_through_;    // per grid coordinate: bends centred there (h, v)
  std::vector<std::uint32_t> copy_scratch_;
  std::vector<std::uint32_t> fan_triangles_;
  UnionFind<std::size_t> fan_groups_;
  std::vector<std::size_t> fan_roots_;
};

}  // namespace tachi::sim
