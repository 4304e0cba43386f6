#include "tachi/sim/solver.hpp"

#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace tachi::sim {

namespace {

/// Sweep position of a spring: its upper row, then a colour such that two springs of one row and
/// colour never share a particle. Sweeping row by row keeps the few rows being worked on in cache
/// (256^2 positions are 1 MB), and inside a row consecutive projections are independent, so the CPU
/// overlaps them; the sweep as a whole stays plain Gauss-Seidel in a fixed order.
std::uint32_t sweep_key(SpringKind k, GridCoord a, GridCoord b) {
  constexpr int kColoursPerRow = 8;
  const int umin = std::min(a.u, b.u);
  const int vmin = std::min(a.v, b.v);
  const bool along_row = a.v == b.v;
  int colour = 0;
  switch (k) {
    case SpringKind::Structural:
      colour = along_row ? umin % 2 : 2;  // (u, u+1) alternate; columns of one row never touch
      break;
    case SpringKind::Shear:
      colour = (b.u - a.u) * (b.v - a.v) > 0 ? 0 : 1;  // diagonals, then anti-diagonals
      break;
    case SpringKind::Bend:
      colour = along_row ? umin % 4 : 4;  // (u, u+2) share ends with (u+2, u+4): four classes
      break;
  }
  return static_cast<std::uint32_t>(vmin * kColoursPerRow + colour);
}

}  // namespace

std::optional<const char*> validate(const SolverParams& p) {
  if (!(p.dt > 0.0F) || !(p.dt <= 1.0F)) return "dt must be in (0, 1] s";
  if (p.substeps < 1 || p.substeps > 64) return "substeps must be in [1, 64]";
  if (p.iterations < 1 || p.iterations > 200) return "iterations must be in [1, 200]";
  if (!p.gravity.allFinite()) return "gravity must be finite";
  if (!(p.damping >= 0.0F) || !std::isfinite(p.damping)) return "damping must be >= 0";
  if (!(p.shear_compliance >= 0.0F) || !(p.bend_compliance >= 0.0F) || !(p.structural_compliance >= 0.0F))
    return "compliance must be >= 0";
  if (!(p.max_strain > 0.0F) || !(p.max_strain < 10.0F)) return "max_strain must be in (0, 10)";
  if (p.strain_limit_passes < 1 || p.strain_limit_passes > 100) return "strain_limit_passes must be in [1, 100]";
  return std::nullopt;
}

Solver::Solver(SolverParams params) : params_(std::move(params)) {}

void Solver::build_groups(const std::vector<PackedSpring>& springs, const std::vector<std::uint32_t>& keys,
                          std::uint32_t dummy, std::vector<Group>& groups) {
  // Four springs of one sweep class (same row and colour) never share a particle on the grid; the check
  // below also keeps that true for springs a cut added or rewired, so the four lanes stay independent.
  groups.clear();
  Group g{};
  int lanes = 0;
  std::uint32_t group_key = 0;
  auto flush = [&] {
    if (lanes == 0) return;
    for (int l = lanes; l < 4; ++l) {
      g.a[l] = dummy;  // padding lane: a particle with inverse mass 0 on both ends does nothing
      g.b[l] = dummy;
      g.rest2[l] = 1.0F;
    }
    groups.push_back(g);
    lanes = 0;
  };
  for (std::size_t k = 0; k < springs.size(); ++k) {
    const PackedSpring& sp = springs[k];
    bool clash = lanes > 0 && keys[k] != group_key;
    for (int l = 0; l < lanes && !clash; ++l) {
      clash = g.a[l] == sp.a || g.a[l] == sp.b || g.b[l] == sp.a || g.b[l] == sp.b;
    }
    if (clash) flush();
    if (lanes == 0) group_key = keys[k];
    g.a[lanes] = sp.a;
    g.b[lanes] = sp.b;
    g.rest2[lanes] = sp.rest * sp.rest;
    if (++lanes == 4) flush();
  }
  flush();
}

void Solver::refresh_caches(const Cloth& cloth) {
  // Anchors: every particle that does not move by itself, pinned or held by the hand (a held particle
  // drags the cloth like a pin, so it gets attachments and the strain limit sweeps out from it too).
  std::vector<std::uint32_t> pins;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_mass[i] == 0.0F) pins.push_back(static_cast<std::uint32_t>(i));
  }
  const bool topology_same = cache_valid_ && cached_version_ == cloth.topology_version &&
                             cached_springs_ == cloth.spring_count() &&
                             cached_particles_ == cloth.particle_count();
  if (topology_same && pins == cached_pins_) return;

  if (!topology_same) {
    // Counting sort by (family, sweep key), keeping spring-index order inside a key: linear time.
    std::uint32_t key_count = 0;
    std::vector<std::uint32_t> key(cloth.spring_count());
    for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
      key[k] = sweep_key(cloth.kind[k], cloth.grid[cloth.spring_a[k]], cloth.grid[cloth.spring_b[k]]);
      key_count = std::max(key_count, key[k] + 1);
    }
    std::vector<PackedSpring>* out[3] = {&structural_, &shear_, &bend_};
    std::vector<std::uint32_t> start;
    for (std::size_t f = 0; f < 3; ++f) {
      const auto family = static_cast<SpringKind>(f);
      start.assign(static_cast<std::size_t>(key_count) + 1, 0);
      std::size_t count = 0;
      for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
        if (cloth.alive[k] == 0 || cloth.kind[k] != family) continue;
        ++start[key[k] + 1];
        ++count;
      }
      for (std::size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
      out[f]->resize(count);
      std::vector<std::uint32_t> sorted_key(count);
      for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
        if (cloth.alive[k] == 0 || cloth.kind[k] != family) continue;
        sorted_key[start[key[k]]] = key[k];
        (*out[f])[start[key[k]]++] = {cloth.spring_a[k], cloth.spring_b[k], cloth.rest_length[k]};
      }
      build_groups(*out[f], sorted_key, static_cast<std::uint32_t>(cloth.particle_count()), groups_[f]);
    }
  }
  cached_pins_ = std::move(pins);
  build_attachments(cloth);
  cached_version_ = cloth.topology_version;
  cached_springs_ = cloth.spring_count();
  cached_particles_ = cloth.particle_count();
  cache_valid_ = true;
}

void Solver::build_attachments(const Cloth& cloth) {
  attachments_.clear();
  strain_limit_.clear();
  const std::size_t n = cloth.particle_count();
  if (cached_pins_.empty()) {
    strain_limit_ = structural_;
    return;
  }
  // Adjacency over live structural and shear springs (rest geometry), CSR form.
  std::vector<std::uint32_t> offsets(n + 1, 0);
  for (const auto* family : {&structural_, &shear_}) {
    for (const PackedSpring& s : *family) {
      ++offsets[s.a + 1];
      ++offsets[s.b + 1];
    }
  }
  for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  std::vector<std::pair<std::uint32_t, float>> edges(offsets[n]);
  std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (const auto* family : {&structural_, &shear_}) {
    for (const PackedSpring& s : *family) {
      edges[fill[s.a]++] = {s.b, s.rest};
      edges[fill[s.b]++] = {s.a, s.rest};
    }
  }
  // Geodesic rest distance from a set of sources (Dijkstra); `owner` says which pin is nearest.
  using Item = std::pair<float, std::uint32_t>;
  std::vector<float> dist(n);
  std::vector<std::uint32_t> owner(n);
  auto dijkstra = [&](const std::vector<std::uint32_t>& sources) {
    std::fill(dist.begin(), dist.end(), std::numeric_limits<float>::infinity());
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (const std::uint32_t s : sources) {
      dist[s] = 0.0F;
      owner[s] = s;
      queue.emplace(0.0F, s);
    }
    while (!queue.empty()) {
      const auto [d, i] = queue.top();
      queue.pop();
      if (d > dist[i]) continue;
      for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
        const auto [j, len] = edges[e];
        if (d + len < dist[j]) {
          dist[j] = d + len;
          owner[j] = owner[i];
          queue.emplace(dist[j], j);
        }
      }
    }
  };
  // Dijkstra over springs measures octile paths, up to 8 % longer than the straight line: that much
  // slack lets the middle of a wide drape sag by centimetres. Where the path is no longer than the
  // octile distance of the two grid coordinates (no cut in the way), the straight rest distance is the
  // geodesic, so it is used instead; behind a cut the path length is kept.
  auto octile = [&](GridCoord a, GridCoord b) {
    const float dx = std::abs(static_cast<float>(a.u - b.u)) * cloth.spacing_x();
    const float dy = std::abs(static_cast<float>(a.v - b.v)) * cloth.spacing_y();
    const float diagonal = std::min(dx / cloth.spacing_x(), dy / cloth.spacing_y());
    return dx + dy - diagonal * (cloth.spacing_x() + cloth.spacing_y()) +
           diagonal * std::hypot(cloth.spacing_x(), cloth.spacing_y());
  };
  auto collect = [&] {
    for (std::size_t i = 0; i < n; ++i) {
      if (cloth.inverse_mass[i] == 0.0F || !std::isfinite(dist[i])) continue;
      const GridCoord gi = cloth.grid[i];
      const GridCoord gp = cloth.grid[owner[i]];
      const bool unobstructed = dist[i] <= octile(gi, gp) * (1.0F + 1e-4F) + 1e-6F;
      const float length = unobstructed ? cloth.grid_rest_length(gi, gp) : dist[i];
      attachments_.push_back({static_cast<std::uint32_t>(i), owner[i], length * length});
    }
  };
  // A few pins (corners): every particle is tethered to each of them. Many pins (an edge): only to
  // its nearest, as Kim et al. do, which keeps the cost at one tether per particle.
  constexpr std::size_t kAllPinsUpTo = 4;
  if (cached_pins_.size() <= kAllPinsUpTo) {
    // One search per pin; the distance to the nearest pin is their minimum.
    std::vector<float> nearest(n, std::numeric_limits<float>::infinity());
    for (const std::uint32_t pin : cached_pins_) {
      dijkstra({pin});
      if (params_.long_range_attachments) collect();
      for (std::size_t i = 0; i < n; ++i) nearest[i] = std::min(nearest[i], dist[i]);
    }
    dist.swap(nearest);
  } else {
    dijkstra(cached_pins_);
    if (params_.long_range_attachments) collect();
  }

  // Provot's deformation constraint is swept outwards from the pins (by geodesic distance of the
  // spring's nearer end): a correction near a pin then reaches the far edge within one sweep more often
  // than in grid order (measured in docs/sim.md). Pieces no pin holds (+inf) come last, in grid order.
  // Counting sort on the distance in half-spacings: linear time, stable, so ties keep grid order.
  const float unit = 0.5F * std::min(cloth.spacing_x(), cloth.spacing_y());
  std::vector<std::uint32_t> level(structural_.size());
  std::uint32_t top = 0;
  for (std::size_t k = 0; k < structural_.size(); ++k) {
    const float key = std::min(dist[structural_[k].a], dist[structural_[k].b]);
    level[k] = std::isfinite(key) ? static_cast<std::uint32_t>(key / unit) : std::numeric_limits<std::uint32_t>::max();
    if (level[k] != std::numeric_limits<std::uint32_t>::max()) top = std::max(top, level[k]);
  }
  std::vector<std::uint32_t> start(static_cast<std::size_t>(top) + 3, 0);
  for (std::uint32_t& l : level) {
    if (l == std::numeric_limits<std::uint32_t>::max()) l = top + 1;  // unpinned pieces last
    ++start[l + 1];
  }
  for (std::size_t l = 1; l < start.size(); ++l) start[l] += start[l - 1];
  std::vector<std::uint32_t> keyed(structural_.size());
  for (std::size_t k = 0; k < structural_.size(); ++k) keyed[start[level[k]]++] = static_cast<std::uint32_t>(k);
  strain_limit_.reserve(keyed.size());
  for (const std::uint32_t k : keyed) strain_limit_.push_back(structural_[k]);
}

void Solver::step(Cloth& cloth, const Colliders& colliders) {
  refresh_caches(cloth);
  const std::size_t n = cloth.particle_count();
  // Work on (x, y, z, w) quadruples: one aligned 16-byte load brings a position and its inverse mass.
  work_.resize(n + 1);
  work_[n] = Eigen::Vector4f::Zero();  // the padding lanes' particle: never moves (inverse mass 0)
  old_work_.resize(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    work_[i] << cloth.position[i], cloth.inverse_mass[i];
  }
  const float h = params_.dt / static_cast<float>(params_.substeps);
  for (int s = 0; s < params_.substeps; ++s) substep(cloth, colliders, h, s == 0);
  for (std::size_t i = 0; i < n; ++i) cloth.position[i] = work_[i].head<3>();
}

namespace {

using Vec4 = Eigen::Vector4f;
const Vec4 kXyz{1.0F, 1.0F, 1.0F, 0.0F};

enum class Length { Exact, NearRest };

/// Projection of one distance constraint C = |xa - xb| - target (Mueller et al. 2007, eq. 10-11), scaled
/// by the XPBD factor 1 / (wa + wb + alpha~) (Macklin et al. 2016, eq. 18 with lambda = 0).
/// Length::NearRest replaces |d| by its first-order expansion around the target, |d| ~ (|d|^2 + L^2) / 2L
/// (Jakobsen 2001, "Advanced Character Physics"): no square root, the same fixed point |d| = L, and a
/// correction that stays bounded (< |d|) however far the spring is compressed or stretched.
template <Length kLength>
inline void project_distance(Vec4& pa, Vec4& pb, float target, float alpha) {
  const float wa = pa.w(), wb = pb.w();
  const float wsum = wa + wb;
  if (wsum == 0.0F) return;
  const Vec4 d = (pb - pa).cwiseProduct(kXyz);
  const float len2 = d.squaredNorm();
  float c = 0.0F;
  if constexpr (kLength == Length::Exact) {
    if (len2 < 1e-18F) return;  // coincident particles: no direction to correct along
    const float len = std::sqrt(len2);
    c = (len - target) / (len * (wsum + alpha));
  } else {
    const float target2 = target * target;
    c = (len2 - target2) / ((len2 + target2) * (wsum + alpha));
  }
  pa += (wa * c) * d;
  pb -= (wb * c) * d;
}

/// project_distance<Length::NearRest> on four independent springs at once (SSE, x86-64 baseline):
/// the same arithmetic per lane, so the sweep is still Gauss-Seidel in the same fixed order.
void sweep_near_rest(Vec4* x, const std::vector<Solver::Group>& groups, float alpha) {
  const __m128 alpha4 = _mm_set1_ps(alpha);
  const __m128 zero = _mm_setzero_ps();
  for (const Solver::Group& g : groups) {
    __m128 a0 = _mm_load_ps(x[g.a[0]].data()), a1 = _mm_load_ps(x[g.a[1]].data());
    __m128 a2 = _mm_load_ps(x[g.a[2]].data()), a3 = _mm_load_ps(x[g.a[3]].data());
    __m128 b0 = _mm_load_ps(x[g.b[0]].data()), b1 = _mm_load_ps(x[g.b[1]].data());
    __m128 b2 = _mm_load_ps(x[g.b[2]].data()), b3 = _mm_load_ps(x[g.b[3]].data());
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);  // a0 = x of the four a's, a1 = y, a2 = z, a3 = inverse mass
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    const __m128 dx = _mm_sub_ps(b0, a0), dy = _mm_sub_ps(b1, a1), dz = _mm_sub_ps(b2, a2);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 rest2 = _mm_load_ps(g.rest2);
    const __m128 wsum = _mm_add_ps(a3, b3);
    const __m128 denominator = _mm_mul_ps(_mm_add_ps(len2, rest2), _mm_add_ps(wsum, alpha4));
    // Both ends fixed (wsum = 0, alpha = 0) would divide by zero: such lanes get c = 0.
    const __m128 c = _mm_and_ps(_mm_div_ps(_mm_sub_ps(len2, rest2), denominator), _mm_cmpgt_ps(wsum, zero));
    const __m128 ca = _mm_mul_ps(a3, c), cb = _mm_mul_ps(b3, c);
    a0 = _mm_add_ps(a0, _mm_mul_ps(ca, dx));
    a1 = _mm_add_ps(a1, _mm_mul_ps(ca, dy));
    a2 = _mm_add_ps(a2, _mm_mul_ps(ca, dz));
    b0 = _mm_sub_ps(b0, _mm_mul_ps(cb, dx));
    b1 = _mm_sub_ps(b1, _mm_mul_ps(cb, dy));
    b2 = _mm_sub_ps(b2, _mm_mul_ps(cb, dz));
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    _mm_store_ps(x[g.a[0]].data(), a0);
    _mm_store_ps(x[g.a[1]].data(), a1);
    _mm_store_ps(x[g.a[2]].data(), a2);
    _mm_store_ps(x[g.a[3]].data(), a3);
    _mm_store_ps(x[g.b[0]].data(), b0);
    _mm_store_ps(x[g.b[1]].data(), b1);
    _mm_store_ps(x[g.b[2]].data(), b2);
    _mm_store_ps(x[g.b[3]].data(), b3);
  }
}

}  // namespace

void Solver::substep(Cloth& cloth, const Colliders& colliders, float h, bool first) {
  const std::size_t n = cloth.particle_count();
  Vec4* x = work_.data();
  Eigen::Vector3f* v = cloth.velocity.data();
  std::copy(work_.begin(), work_.end(), old_work_.begin());

  // 1. Prediction (symplectic Euler on external forces; seed 000's point-cloud repulsion is one of them).
  const float keep = std::max(0.0F, 1.0F - params_.damping * h);
  const Eigen::Vector3f gh = params_.gravity * h;
  const PointCloudCollider* cloud = colliders.point_cloud;
  for (std::size_t i = 0; i < n; ++i) {
    if (x[i].w() == 0.0F) continue;
    Eigen::Vector3f vel = v[i] * keep + gh;
    if (cloud != nullptr) vel += cloud->repulsion(x[i].head<3>()) * h;
    v[i] = vel;
    x[i].head<3>() += vel * h;
  }

  // 2. Long-range attachments (unilateral): a particle may not be farther from a pin than its rest
  // distance, which removes in one pass the sag that Gauss-Seidel needs O(N^2) passes for.
  for (const Attachment& a : attachments_) {
    Vec4& p = x[a.particle];
    if (p.w() == 0.0F) continue;
    const Vec4& anchor = x[a.pin];
    const Vec4 d = (p - anchor).cwiseProduct(kXyz);
    const float len2 = d.squaredNorm();
    if (len2 > a.length2) p.head<3>() = anchor.head<3>() + d.head<3>() * std::sqrt(a.length2 / len2);
  }

  // 3. Soft shear and bend springs, one XPBD pass each per sub-step (soft: more passes buy nothing visible).
  if (first || params_.soft_every_substep) {
    const float full_h = params_.soft_every_substep ? h : params_.dt;
    const float shear_alpha = params_.shear_compliance / (full_h * full_h);
    const float bend_alpha = params_.bend_compliance / (full_h * full_h);
    sweep_near_rest(x, groups_[1], shear_alpha);
    sweep_near_rest(x, groups_[2], bend_alpha);
  }

  // 4. Structural springs, hard, Gauss-Seidel. Near rest length the square root is replaced by its
  // first-order expansion, |d| ~ (|d|^2 + L^2) / 2L (Jakobsen 2001, "Advanced Character Physics"):
  // the fixed point is still |d| = L, and step 5 below is exact.
  const float structural_alpha = params_.structural_compliance / (h * h);
  for (int it = 0; it < params_.iterations; ++it) {
    sweep_near_rest(x, groups_[0], structural_alpha);
  }

  // 5. Provot's deformation constraint: a structural spring longer than (1 + max_strain) L is brought
  // back (Provot 1995, section 4), sweeping outwards from the pins.
  // A violating spring is brought to 95 % of the allowed stretch, not exactly to it: the corrections of
  // its neighbours then push it back towards, not over, the limit (a 256^2 cloth otherwise rests with a
  // few springs at 10.08 %).
  const float limit = 1.0F + params_.max_strain;
  const float corrected = 1.0F + 0.95F * params_.max_strain;
  // A correction can stretch a spring swept earlier, so sweeps repeat until one finds nothing to
  // correct (usually the first: the scan without a square root is cheap) or the budget is spent.
  for (int pass = 0; pass < params_.strain_limit_passes; ++pass) {
    std::size_t corrections = 0;
    for (const PackedSpring& s : strain_limit_) {
      const Vec4 d = (x[s.b] - x[s.a]).cwiseProduct(kXyz);
      const float target = limit * s.rest;
      if (d.squaredNorm() > target * target) {
        project_distance<Length::Exact>(x[s.a], x[s.b], corrected * s.rest, 0.0F);
        ++corrections;
      }
    }
    if (corrections == 0) break;
  }

  // 6. Collisions by projection with friction (collide_with_friction), then velocities from the positions
  // actually reached.
  const bool any_collider = !colliders.spheres.empty() || !colliders.boxes.empty() || colliders.ground.has_value() ||
                            cloud != nullptr;
  if (any_collider) {
    for (std::size_t i = 0; i < n; ++i) {
      if (x[i].w() == 0.0F) continue;
      Eigen::Vector3f p = x[i].head<3>();
      if (collide_with_friction(p, old_work_[i].head<3>(), colliders, h)) x[i].head<3>() = p;
    }
  }
  const float inv_h = 1.0F / h;
  for (std::size_t i = 0; i < n; ++i) {
    if (x[i].w() == 0.0F) continue;
    v[i] = (x[i].head<3>() - old_work_[i].head<3>()) * inv_h;
  }

}

double mechanical_energy(const Cloth& cloth, const Eigen::Vector3f& gravity, double k_structural) {
  double e = 0.0;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    const double m = cloth.mass[i];
    e += 0.5 * m * static_cast<double>(cloth.velocity[i].squaredNorm());
    e -= m * static_cast<double>(gravity.dot(cloth.position[i]));
  }
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] != SpringKind::Structural) continue;
    const double len = (cloth.position[cloth.spring_a[k]] - cloth.position[cloth.spring_b[k]]).norm();
    const double stretch = len - static_cast<double>(cloth.rest_length[k]);
    e += 0.5 * k_structural * stretch * stretch;
  }
  return e;
}

}  // namespace tachi::sim
