#include "tachi/sim/pieces.hpp"

#include "tachi/sim/union_find.hpp"

#include <algorithm>

namespace tachi::sim {

std::size_t Pieces::fallen() const {
  return static_cast<std::size_t>(std::count(pinned.begin(), pinned.end(), std::uint8_t{0}));
}

std::size_t Pieces::cloth_count() const {
  return static_cast<std::size_t>(std::count(cloth.begin(), cloth.end(), std::uint8_t{1}));
}

std::size_t Pieces::cloth_fallen() const {
  std::size_t n = 0;
  for (std::size_t p = 0; p < size.size(); ++p) n += cloth[p] != 0 && pinned[p] == 0 ? 1U : 0U;
  return n;
}

std::size_t Pieces::loose_particles() const {
  std::size_t n = 0;
  for (std::size_t p = 0; p < size.size(); ++p) n += cloth[p] == 0 ? size[p] : 0U;
  return n;
}

Pieces find_pieces(const Cloth& cloth) {
  const std::size_t n = cloth.particle_count();
  UnionFind<std::uint32_t> sets(n);
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] != 0) sets.unite(cloth.spring_a[k], cloth.spring_b[k]);
  }
  Pieces out;
  out.piece_of.assign(n, 0);
  std::vector<std::uint32_t> label(n, 0xFFFFFFFFU);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = sets.find(i);
    if (label[r] == 0xFFFFFFFFU) {
      label[r] = static_cast<std::uint32_t>(out.size.size());
      out.size.push_back(0);
      out.pinned.push_back(0);
    }
    const std::uint32_t piece = label[r];
    out.piece_of[i] = piece;
    ++out.size[piece];
    if (cloth.pinned[i] != 0) out.pinned[piece] = 1;
  }
  out.cloth.assign(out.size.size(), cloth.triangle_count() == 0 ? 1 : 0);
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] != 0) out.cloth[out.piece_of[cloth.triangles[t][0]]] = 1;
  }
  return out;
}

}  // namespace tachi::sim
