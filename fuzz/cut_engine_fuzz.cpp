// libFuzzer target: the cut engine (seed 000 sections 3.1-3.3, sim/src/stroke.cpp, cutting.cpp and
// exact_cut.cpp) on random strokes over random grids, in every cut mode. The bytes choose the grid (2..24
// per side), the pinning, the blade, the cut mode (exact, grid or delete) and the hand's path (positions
// may lie far beyond the cloth); solver steps run between samples so the cloth deforms. After every stroke the mesh invariants must hold: every spring and
// triangle names existing particles and is in their incidence lists, no spring joins a particle to
// itself, the particle arrays agree in size, mass is conserved (no particle's negative) and every position
// and rest coordinate stays finite.
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <numeric>

namespace {

class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  std::uint8_t next() { return pos_ < size_ ? data_[pos_++] : 0; }
  /// A coordinate in [-1.5, 1.5] m: a 1 m cloth and half a metre beyond each edge.
  float coordinate() { return (static_cast<float>(next()) / 255.0F - 0.5F) * 3.0F; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

void require(bool ok) {
  if (!ok) std::abort();
}

void check_invariants(const tachi::sim::Cloth& cloth, double mass_before) {
  const std::size_t n = cloth.particle_count();
  require(cloth.velocity.size() == n && cloth.mass.size() == n && cloth.inverse_mass.size() == n &&
          cloth.grid.size() == n && cloth.pinned.size() == n && cloth.rest_uv.size() == n);
  const double mass = std::accumulate(cloth.mass.begin(), cloth.mass.end(), 0.0);
  require(std::abs(mass - mass_before) <= 1e-4 * mass_before);
  for (std::size_t i = 0; i < n; ++i) {
    require(cloth.position[i].allFinite() && cloth.rest_uv[i].allFinite() && cloth.mass[i] >= 0.0F);
    require(cloth.grid[i].u >= 0 && cloth.grid[i].u < cloth.columns && cloth.grid[i].v >= 0 && cloth.grid[i].v < cloth.rows);
  }
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0) continue;
    const std::uint32_t a = cloth.spring_a[k];
    const std::uint32_t b = cloth.spring_b[k];
    require(a < n && b < n && a != b);
    const auto sa = cloth.springs_of(a);
    const auto sb = cloth.springs_of(b);
    require(std::find(sa.begin(), sa.end(), k) != sa.end() && std::find(sb.begin(), sb.end(), k) != sb.end());
  }
  for (std::uint32_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    for (const std::uint32_t p : cloth.triangles[t]) {
      require(p < n);
      const auto tp = cloth.triangles_of(p);
      require(std::find(tp.begin(), tp.end(), t) != tp.end());
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tachi::sim;
  Bytes bytes(data, size);
  ClothConfig config;
  config.columns = 2 + bytes.next() % 23;
  config.rows = 2 + bytes.next() % 23;
  config.pin = static_cast<PinMode>(bytes.next() % 3);
  Cloth cloth{config};
  StrokeOptions options;
  options.blade = static_cast<Blade>(bytes.next() % 6);
  options.mode = static_cast<CutMode>(bytes.next() % 3);  // exact, grid, delete
  StrokeCutter cutter{cloth, options};
  Solver solver;
  const double mass = std::accumulate(cloth.mass.begin(), cloth.mass.end(), 0.0);
  double t = 0.0;
  while (!bytes.empty()) {
    const std::uint8_t op = bytes.next();
    if (op < 200) {
      cutter.add_sample({t, Eigen::Vector3f{bytes.coordinate(), bytes.coordinate(), bytes.coordinate() * 0.1F}});
      t += 1.0 / 30.0;
    } else if (op < 240) {
      solver.step(cloth);
    } else {
      cutter.end_stroke();
      check_invariants(cloth, mass);
    }
  }
  cutter.end_stroke();
  check_invariants(cloth, mass);
  return 0;
}
