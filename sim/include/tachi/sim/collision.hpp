// Colliders the cloth cannot enter: simple shapes (sphere, box, ground plane; the hand is a sphere)
// resolved by projecting particles to the surface (position-based, Mueller et al. 2007, section 3.5),
// and an object given as a point cloud pushing particles away with a repulsive force that grows as the
// distance to the nearest object point shrinks (seed 000 section 2, Mesuda et al.).
#pragma once

#include "tachi/sim/cloth.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace tachi::sim {

struct Sphere {
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  float radius = 0.1F;
};

/// Axis-aligned box.
struct Box {
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  Eigen::Vector3f half_extent = Eigen::Vector3f::Constant(0.1F);
};

/// Half-space below the plane y = height is solid.
struct GroundPlane {
  float height = -1.0F;
};

/// An object model as a point cloud with a kd-tree (nanoflann) for nearest-point queries.
class PointCloudCollider {
 public:
  /// `influence_m`: distance below which a particle is repelled; `stiffness`: acceleration (m/s^2)
  /// applied at zero distance, falling linearly to 0 at `influence_m` (seed 000: repulsion from distance).
  /// Non-finite points are dropped.
  PointCloudCollider(std::vector<Eigen::Vector3f> points, float influence_m, float stiffness);
  ~PointCloudCollider();
  PointCloudCollider(const PointCloudCollider&) = delete;
  PointCloudCollider& operator=(const PointCloudCollider&) = delete;

  /// Nearest object point within `influence_m` of p, if any.
  [[nodiscard]] std::optional<Eigen::Vector3f> nearest_within(const Eigen::Vector3f& p) const;
  /// Repulsive acceleration on a particle at p (zero outside the influence distance).
  [[nodiscard]] Eigen::Vector3f repulsion(const Eigen::Vector3f& p) const;
  /// Keeps p at least `contact_m` from the nearest object point, pushing it out on the side it came
  /// from (`previous`): the cloud has no inside, so a particle that crossed a layer of points in one
  /// sub-step goes back, not through. Within the influence distance the particle touches the object:
  /// returns the contact normal (unit, away from the nearest point, on the particle's side) and how far
  /// the object pushed it along the normal in a sub-step of `h` seconds (the projection plus the
  /// repulsion's h^2 a), which bounds the friction; nothing when it is farther.
  struct Contact {
    Eigen::Vector3f normal;
    float push_m;
  };
  std::optional<Contact> project(Eigen::Vector3f& p, const Eigen::Vector3f& previous, float contact_m, float h) const;
  [[nodiscard]] float influence() const { return influence_; }
  [[nodiscard]] const std::vector<Eigen::Vector3f>& points() const { return points_; }

 private:
  struct Index;  // the kd-tree, kept out of this header
  std::vector<Eigen::Vector3f> points_;
  float influence_;
  float stiffness_;
  std::unique_ptr<Index> index_;
};

/// Everything the cloth collides with in one step. The hand is one of the spheres.
struct Colliders {
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
  std::optional<GroundPlane> ground;
  const PointCloudCollider* point_cloud = nullptr;  ///< not owned; may be null
  float thickness_m = 0.005F;                        ///< particles keep this far from surfaces
  float friction = 0.5F;  ///< 0..1: share of a touching particle's sliding that contact removes per sub-step
  /// Distance a particle keeps from every point of `point_cloud` (0: half its influence distance).
  float point_contact_m = 0.0F;
};

/// Moves p out of every collider (shapes, then the point cloud) and applies friction to the sliding that
/// this sub-step (`h` seconds, from `previous`) made across the contact. Shapes: `friction` of it is
/// removed (position-based friction, Macklin et al. 2014, section 6.1, in its simplest form). The point
/// cloud: Coulomb friction with coefficient `friction` against the object's normal push (Macklin et al.
/// 2014, eq. 24-25): sliding below friction x push sticks, above it is reduced by that much, so a cloth
/// on an object stays instead of creeping off. Returns true if p was in contact.
bool collide_with_friction(Eigen::Vector3f& p, const Eigen::Vector3f& previous, const Colliders& colliders, float h);

/// Moves p out of a sphere grown by `margin` (closest surface point). Returns true if it moved.
bool project_out_of_sphere(Eigen::Vector3f& p, const Sphere& s, float margin);
/// Moves p out of a box grown by `margin` along the axis of least penetration. Returns true if it moved.
bool project_out_of_box(Eigen::Vector3f& p, const Box& b, float margin);
/// Lifts p to y = height + margin if below. Returns true if it moved.
bool project_above_ground(Eigen::Vector3f& p, const GroundPlane& g, float margin);

/// Moves p out of every shape collider (spheres, boxes, ground). Returns true if it moved.
bool project_out_of_shapes(Eigen::Vector3f& p, const Colliders& colliders);

/// Projects every movable particle (inverse mass > 0) out of the shape colliders. Returns the count moved.
std::size_t resolve_shape_collisions(Cloth& cloth, const Colliders& colliders);

}  // namespace tachi::sim
