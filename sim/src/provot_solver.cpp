#include "tachi/sim/provot_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tachi::sim {

std::optional<std::string> validate(const ProvotParams& p) {
  if (!(p.dt > 0.0F) || !(p.dt <= 1.0F)) return "dt must be in (0, 1] s";
  if (p.substeps < 1 || p.substeps > 512) return "--substeps must be in [1, 512] for --solver provot";
  if (!p.gravity.allFinite()) return "gravity must be finite";
  if (auto bad = validate(p.material)) return bad;
  if (!std::isfinite(p.spring_damping_ratio) || p.spring_damping_ratio < 0.0F || p.spring_damping_ratio > 1.0F)
    return "spring damping ratio must be in [0, 1]";
  if (!(p.max_strain > 0.0F) || !(p.max_strain < 10.0F)) return "max_strain must be in (0, 10)";
  if (p.correction_passes < 1 || p.correction_passes > 1000) return "correction passes must be in [1, 1000]";
  return std::nullopt;
}

ProvotSolver::ProvotSolver(ProvotParams params) : params_(std::move(params)) {}

void ProvotSolver::refresh(const Cloth& cloth) {
  std::vector<std::uint32_t> fixed;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_mass[i] == 0.0F) fixed.push_back(static_cast<std::uint32_t>(i));
  }
  if (cache_valid_ && cached_version_ == cloth.topology_version && cached_springs_ == cloth.spring_count() &&
      cached_particles_ == cloth.particle_count() && fixed == cached_fixed_)
    return;
  cached_fixed_ = std::move(fixed);
  const SpringStiffness k = spring_stiffness(params_.material, cloth.spacing_x(), cloth.spacing_y());
  // Stability cap: h^2 * (sum of the spring constants at a particle) / m <= 1, half the explicit limit.
  // A grid particle has 4 springs of each family; the lightest particle (a cut halves masses) decides.
  float m_min = 0.0F;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_mass[i] > 0.0F && (m_min == 0.0F || cloth.mass[i] < m_min)) m_min = cloth.mass[i];
  }
  const float h = params_.dt / static_cast<float>(params_.substeps);
  const float sum_k = 4.0F * (k.structural + k.shear + k.bend);
  scale_ = m_min > 0.0F ? std::min(1.0F, m_min / (h * h * sum_k)) : 1.0F;
  used_ = {k.structural * scale_, k.shear * scale_, k.bend * scale_};

  springs_.clear();
  limited_.clear();
  for (std::size_t s = 0; s < cloth.spring_count(); ++s) {
    if (cloth.alive[s] == 0) continue;
    const SpringKind kind = cloth.kind[s];
    const float ks = kind == SpringKind::Structural ? used_.structural : kind == SpringKind::Shear ? used_.shear : used_.bend;
    const float m = 0.5F * (cloth.mass[cloth.spring_a[s]] + cloth.mass[cloth.spring_b[s]]);
    const float c = params_.spring_damping_ratio * 2.0F * std::sqrt(ks * m);
    const bool limited = kind != SpringKind::Bend;
    if (limited) limited_.push_back(static_cast<std::uint32_t>(springs_.size()));
    springs_.push_back({cloth.spring_a[s], cloth.spring_b[s], cloth.rest_length[s], ks, c, limited});
  }
  order_outwards(cloth);
  cached_version_ = cloth.topology_version;
  cached_springs_ = cloth.spring_count();
  cached_particles_ = cloth.particle_count();
  cache_valid_ = true;
}

void ProvotSolver::order_outwards(const Cloth& cloth) {
  // Breadth-first hop count from the fixed particles over the constrained springs: sweeping the
  // deformation constraint in that order carries a correction from a pin to the far edge in one sweep
  // (in index order it needs one sweep per row), the same reason the PBD solver sweeps from its pins.
  const std::size_t n = cloth.particle_count();
  std::vector<std::vector<std::uint32_t>> next(n);
  for (const std::uint32_t k : limited_) {
    next[springs_[k].a].push_back(springs_[k].b);
    next[springs_[k].b].push_back(springs_[k].a);
  }
  constexpr std::uint32_t kUnreached = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> hops(n, kUnreached);
  std::vector<std::uint32_t> queue(cached_fixed_.begin(), cached_fixed_.end());
  for (const std::uint32_t f : queue) hops[f] = 0;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::uint32_t i = queue[head];
    for (const std::uint32_t j : next[i]) {
      if (hops[j] != kUnreached) continue;
      hops[j] = hops[i] + 1;
      queue.push_back(j);
    }
  }
  std::stable_sort(limited_.begin(), limited_.end(), [&](std::uint32_t x, std::uint32_t y) {
    return std::min(hops[springs_[x].a], hops[springs_[x].b]) < std::min(hops[springs_[y].a], hops[springs_[y].b]);
  });
}

void ProvotSolver::step(Cloth& cloth, const Colliders& colliders) {
  refresh(cloth);
  const float h = params_.dt / static_cast<float>(params_.substeps);
  for (int s = 0; s < params_.substeps; ++s) substep(cloth, colliders, h);
}

void ProvotSolver::substep(Cloth& cloth, const Colliders& colliders, float h) {
  const std::size_t n = cloth.particle_count();
  auto& x = cloth.position;
  auto& v = cloth.velocity;
  const auto& w = cloth.inverse_mass;

  // 1. Forces (Provot 1995 eq. 1-4): gravity, air drag, springs with a viscous term along each spring.
  force_.resize(n);
  const float air = params_.material.damping_per_s;
  for (std::size_t i = 0; i < n; ++i) force_[i] = cloth.mass[i] * (params_.gravity - air * v[i]);
  for (const PackedSpring& s : springs_) {
    const Eigen::Vector3f d = x[s.b] - x[s.a];
    const float len = d.norm();
    if (len < 1e-9F) continue;
    const Eigen::Vector3f u = d / len;
    const float f = s.k * (len - s.rest) + s.c * (v[s.b] - v[s.a]).dot(u);
    force_[s.a] += f * u;
    force_[s.b] -= f * u;
  }
  if (colliders.point_cloud != nullptr) {
    for (std::size_t i = 0; i < n; ++i) force_[i] += cloth.mass[i] * colliders.point_cloud->repulsion(x[i]);
  }

  // 2. Symplectic Euler.
  start_.assign(x.begin(), x.end());
  for (std::size_t i = 0; i < n; ++i) {
    if (w[i] == 0.0F) continue;
    v[i] += h * w[i] * force_[i];
    x[i] += h * v[i];
  }

  // 3. Deformation constraint (Provot 1995 section 5): over-stretched springs are shortened to the
  // critical length, both ends half-way, a fixed end not at all. As in the PBD solver, a violating spring
  // is brought to 95 % of the allowed stretch so its neighbours' corrections do not push it back over.
  const float limit = 1.0F + params_.max_strain;
  const float target = 1.0F + 0.95F * params_.max_strain;
  for (int pass = 0; pass < params_.correction_passes; ++pass) {
    std::size_t corrections = 0;
    for (const std::uint32_t k : limited_) {
      const PackedSpring& s = springs_[k];
      const float wa = w[s.a], wb = w[s.b];
      if (wa + wb == 0.0F) continue;
      const Eigen::Vector3f d = x[s.b] - x[s.a];
      const float len2 = d.squaredNorm();
      const float max_len = limit * s.rest;
      if (len2 <= max_len * max_len) continue;
      const float len = std::sqrt(len2);
      const Eigen::Vector3f excess = d * ((len - target * s.rest) / len);
      // Provot moves each free end by half the excess; a fixed end leaves it all to the other.
      const float share_a = wb == 0.0F ? 1.0F : wa == 0.0F ? 0.0F : 0.5F;
      x[s.a] += share_a * excess;
      x[s.b] -= (1.0F - share_a) * excess;
      ++corrections;
    }
    if (corrections == 0) break;
  }

  // 4. Collisions with friction, then velocities from the positions reached.
  const float inv_h = 1.0F / h;
  for (std::size_t i = 0; i < n; ++i) {
    if (w[i] == 0.0F) continue;
    collide_with_friction(x[i], start_[i], colliders, h);
    v[i] = (x[i] - start_[i]) * inv_h;
  }
}

}  // namespace tachi::sim
