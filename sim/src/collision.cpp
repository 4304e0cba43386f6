#include "tachi/sim/collision.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tachi::sim {

PointCloudCollider::PointCloudCollider(std::vector<Eigen::Vector3f> points, float influence_m, float stiffness)
    : points_(std::move(points)), influence_(std::max(influence_m, 1e-4F)), stiffness_(stiffness) {
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite()) continue;  // a bad sample is skipped, not fatal
    const Eigen::Vector3i c = cell_of(points_[i]);
    cells_[key(c.x(), c.y(), c.z())].push_back(static_cast<std::uint32_t>(i));
  }
}

std::int64_t PointCloudCollider::key(int x, int y, int z) const {
  // 21 bits per axis is +-1e6 cells: far beyond any scene the sensor sees.
  constexpr std::int64_t mask = (1 << 21) - 1;
  return ((static_cast<std::int64_t>(x) & mask) << 42) | ((static_cast<std::int64_t>(y) & mask) << 21) |
         (static_cast<std::int64_t>(z) & mask);
}

Eigen::Vector3i PointCloudCollider::cell_of(const Eigen::Vector3f& p) const {
  return (p / influence_).array().floor().cast<int>();
}

std::optional<Eigen::Vector3f> PointCloudCollider::nearest_within(const Eigen::Vector3f& p) const {
  if (!p.allFinite()) return std::nullopt;
  const Eigen::Vector3i c = cell_of(p);
  float best = influence_ * influence_;
  std::optional<Eigen::Vector3f> out;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = cells_.find(key(c.x() + dx, c.y() + dy, c.z() + dz));
        if (it == cells_.end()) continue;
        for (const std::uint32_t i : it->second) {
          const float d2 = (points_[i] - p).squaredNorm();
          if (d2 < best) {
            best = d2;
            out = points_[i];
          }
        }
      }
    }
  }
  return out;
}

Eigen::Vector3f PointCloudCollider::repulsion(const Eigen::Vector3f& p) const {
  const auto q = nearest_within(p);
  if (!q) return Eigen::Vector3f::Zero();
  const Eigen::Vector3f away = p - *q;
  const float d = away.norm();
  if (d < 1e-9F) return Eigen::Vector3f::Zero();  // no direction to push along
  return away / d * (stiffness_ * (1.0F - d / influence_));
}

bool project_out_of_sphere(Eigen::Vector3f& p, const Sphere& s, float margin) {
  const Eigen::Vector3f d = p - s.centre;
  const float r = s.radius + margin;
  const float n2 = d.squaredNorm();
  if (!(n2 < r * r)) return false;  // also false for a NaN collider: bad input never poisons the cloth
  const float n = std::sqrt(n2);
  // A particle exactly at the centre has no outward direction: push it towards +z (the viewer).
  p = s.centre + (n > 1e-9F ? Eigen::Vector3f{d / n} : Eigen::Vector3f::UnitZ()) * r;
  return true;
}

bool project_out_of_box(Eigen::Vector3f& p, const Box& b, float margin) {
  const Eigen::Vector3f local = p - b.centre;
  const Eigen::Vector3f half = b.half_extent.array() + margin;
  const Eigen::Vector3f depth = half.array() - local.array().abs();
  if (!(depth.array() > 0.0F).all()) return false;  // outside, or NaN
  Eigen::Index axis = 0;
  depth.minCoeff(&axis);
  p[axis] = b.centre[axis] + (local[axis] >= 0.0F ? half[axis] : -half[axis]);
  return true;
}

bool project_above_ground(Eigen::Vector3f& p, const GroundPlane& g, float margin) {
  if (!(p.y() < g.height + margin)) return false;
  p.y() = g.height + margin;
  return true;
}

bool project_out_of_shapes(Eigen::Vector3f& p, const Colliders& colliders) {
  const float margin = colliders.thickness_m;
  bool hit = false;
  for (const Sphere& s : colliders.spheres) hit = project_out_of_sphere(p, s, margin) || hit;
  for (const Box& b : colliders.boxes) hit = project_out_of_box(p, b, margin) || hit;
  if (colliders.ground) hit = project_above_ground(p, *colliders.ground, margin) || hit;
  return hit;
}

std::size_t resolve_shape_collisions(Cloth& cloth, const Colliders& colliders) {
  std::size_t moved = 0;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_mass[i] == 0.0F) continue;
    moved += project_out_of_shapes(cloth.position[i], colliders) ? 1U : 0U;
  }
  return moved;
}

}  // namespace tachi::sim
