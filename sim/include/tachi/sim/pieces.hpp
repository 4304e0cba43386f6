// Connected pieces of a cut cloth: seed 000 section 5 asks for cutting OFF (not only slits), and seed 001
// lets every piece with no path to a fixed point fall under gravity. Pieces are the connected components
// of the particles over live springs; a piece holding no pinned particle is "fallen" (nothing holds it,
// so the solver lets gravity take it).
#pragma once

#include "tachi/sim/cloth.hpp"

#include <cstdint>
#include <vector>

namespace tachi::sim {

struct Pieces {
  std::vector<std::uint32_t> piece_of;   ///< per particle: its piece, 0 .. count - 1
  std::vector<std::uint32_t> size;       ///< per piece: number of particles
  std::vector<std::uint8_t> pinned;      ///< per piece: 1 when it holds a pinned particle
  [[nodiscard]] std::size_t count() const { return size.size(); }
  [[nodiscard]] std::size_t fallen() const;
};

/// Union-find over the live springs, O(particles + springs).
[[nodiscard]] Pieces find_pieces(const Cloth& cloth);

}  // namespace tachi::sim
