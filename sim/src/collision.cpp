#include "tachi/sim/collision.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tachi::sim {

namespace {
/// nanoflann's dataset adaptor over the collider's points.
struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>* points;
  [[nodiscard]] std::size_t kdtree_get_point_count() const { return points->size(); }
  [[nodiscard]] float kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)[i][static_cast<Eigen::Index>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box& /*box*/) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CloudAdaptor>, CloudAdaptor, 3, std::uint32_t>;
}  // namespace

struct PointCloudCollider::Index {
  CloudAdaptor adaptor;
  KdTree tree;
  explicit Index(const std::vector<Eigen::Vector3f>& points)
      : adaptor{&points}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
};

PointCloudCollider::PointCloudCollider(std::vector<Eigen::Vector3f> points, float influence_m, float stiffness)
    : influence_(std::max(influence_m, 1e-4F)), stiffness_(stiffness) {
  points_.reserve(points.size());
  for (const Eigen::Vector3f& p : points) {
    if (p.allFinite()) points_.push_back(p);  // a bad sample is skipped, not fatal
  }
  if (!points_.empty()) index_ = std::make_unique<Index>(points_);
}

PointCloudCollider::~PointCloudCollider() = default;

std::optional<Eigen::Vector3f> PointCloudCollider::nearest_within(const Eigen::Vector3f& p) const {
  if (!index_ || !p.allFinite()) return std::nullopt;
  std::uint32_t nearest = 0;
  float d2 = 0.0F;
  if (index_->tree.knnSearch(p.data(), 1, &nearest, &d2) == 0 || !(d2 < influence_ * influence_)) return std::nullopt;
  return points_[nearest];
}

Eigen::Vector3f PointCloudCollider::repulsion(const Eigen::Vector3f& p) const {
  const auto q = nearest_within(p);
  if (!q) return Eigen::Vector3f::Zero();
  const Eigen::Vector3f away = p - *q;
  const float d = away.norm();
  if (d < 1e-9F) return Eigen::Vector3f::Zero();  // no direction to push along
  return away / d * (stiffness_ * (1.0F - d / influence_));
}

std::optional<PointCloudCollider::Contact> PointCloudCollider::project(Eigen::Vector3f& p, const Eigen::Vector3f& previous,
                                                                      float contact_m, float h) const {
  const auto q = nearest_within(p);
  if (!q) return std::nullopt;
  Eigen::Vector3f away = p - *q;
  // Which side of the point layer the particle belongs to: the side it came from.
  const Eigen::Vector3f from = previous - *q;
  if (away.dot(from) < 0.0F || away.squaredNorm() < 1e-18F) away = from;
  const float n = away.norm();
  if (!(n > 1e-9F)) return std::nullopt;  // came from exactly the point: no side to push to
  const Eigen::Vector3f normal = away / n;
  const float distance = (p - *q).dot(normal);
  float push = stiffness_ * std::max(0.0F, 1.0F - std::abs(distance) / influence_) * h * h;
  if (distance < contact_m) {
    p = *q + normal * contact_m;
    push += contact_m - distance;
  }
  return Contact{normal, push};
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

namespace {
/// The part of the motion previous -> p across the normal n (unit or not).
Eigen::Vector3f tangential_motion(const Eigen::Vector3f& p, const Eigen::Vector3f& previous, const Eigen::Vector3f& n) {
  const Eigen::Vector3f moved = p - previous;
  return moved - n * (moved.dot(n) / n.squaredNorm());
}
}  // namespace

bool collide_with_friction(Eigen::Vector3f& p, const Eigen::Vector3f& previous, const Colliders& colliders, float h) {
  const Eigen::Vector3f before = p;
  bool hit = false;
  if (project_out_of_shapes(p, colliders)) {
    hit = true;
    const Eigen::Vector3f push = p - before;
    if (push.squaredNorm() > 0.0F) p -= colliders.friction * tangential_motion(p, previous, push);
  }
  if (colliders.point_cloud != nullptr) {
    const float contact = colliders.point_contact_m > 0.0F ? colliders.point_contact_m : 0.5F * colliders.point_cloud->influence();
    if (const auto c = colliders.point_cloud->project(p, previous, contact, h)) {
      hit = true;
      const Eigen::Vector3f slide = tangential_motion(p, previous, c->normal);
      const float length = slide.norm();
      const float limit = colliders.friction * c->push_m;
      p -= length <= limit ? slide : Eigen::Vector3f{slide * (limit / length)};
    }
  }
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
