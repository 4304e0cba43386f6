// Connected pieces of a cut cloth: seed 000 section 5 asks for cutting OFF (not only slits), and seed 001
// lets every piece with no path to a fixed point fall under gravity. Pieces are the connected components
// of the particles over live springs; a piece holding no pinned particle is "fallen" (nothing holds it,
// so the solver lets gravity take it). What is reported as a cloth's pieces (the summary, a cut's event,
// the viewer's HUD) are the pieces of cloth: those with a live triangle. Delete mode's completeCUT (seed 001
// section 4) leaves particles in no triangle, each a component of its own; they have no area, are not drawn
// and are not exported, and a slit cut once in delete mode left 60 of them, reported as 60 fallen pieces.
// They are counted apart, as loose particles.
#pragma once

#include "tachi/sim/cloth.hpp"

#include <cstdint>
#include <vector>

namespace tachi::sim {

struct Pieces {
  std::vector<std::uint32_t> piece_of;   ///< per particle: its piece, 0 .. count - 1
  std::vector<std::uint32_t> size;       ///< per piece: number of particles
  std::vector<std::uint8_t> pinned;      ///< per piece: 1 when it holds a pinned particle
  /// per piece: 1 when it has a live triangle, a piece of cloth (every piece of a cloth with no triangles)
  std::vector<std::uint8_t> cloth;
  /// Components of the particles over live springs (what piece_of numbers).
  [[nodiscard]] std::size_t count() const { return size.size(); }
  [[nodiscard]] std::size_t fallen() const;
  /// Pieces of cloth, and those of them nothing pins: what a cut is reported to have made.
  [[nodiscard]] std::size_t cloth_count() const;
  [[nodiscard]] std::size_t cloth_fallen() const;
  /// Particles in no piece of cloth (delete mode's completeCUT leaves them in no triangle).
  [[nodiscard]] std::size_t loose_particles() const;
};

/// Union-find over the live springs, O(particles + springs + triangles).
[[nodiscard]] Pieces find_pieces(const Cloth& cloth);

}  // namespace tachi::sim
