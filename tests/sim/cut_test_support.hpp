// Helpers shared by the cutting tests (grid and exact): small cloths and what a cut must keep.
#pragma once

#include "tachi/sim/cloth.hpp"

#include <cstdint>
#include <numeric>
#include <set>
#include <vector>

namespace tachi::sim::test {

inline Cloth make_cloth(int columns, int rows, PinMode pin = PinMode::TopEdge) {
  ClothConfig config;
  config.columns = columns;
  config.rows = rows;
  config.pin = pin;
  return Cloth{config};
}

inline double total_mass(const Cloth& cloth) { return std::accumulate(cloth.mass.begin(), cloth.mass.end(), 0.0); }

/// Number of connected pieces when particles are joined only through shared triangles.
inline std::size_t triangle_pieces(const Cloth& cloth) {
  std::vector<std::uint32_t> parent(cloth.particle_count());
  std::iota(parent.begin(), parent.end(), 0U);
  const auto find = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    parent[find(tri[1])] = find(tri[0]);
    parent[find(tri[2])] = find(tri[0]);
  }
  std::set<std::uint32_t> roots;
  for (std::uint32_t i = 0; i < cloth.particle_count(); ++i) roots.insert(find(i));
  return roots.size();
}

}  // namespace tachi::sim::test
