// Colliders the cloth cannot enter: simple shapes (sphere, box, ground plane; the hand is a sphere)
// resolved by projecting particles to the surface (position-based, Mueller et al. 2007, section 3.5),
// and an object given as a point cloud pushing particles away with a repulsive force that grows as the
// distance to the nearest object point shrinks (seed 000 section 2, Mesuda et al.).
#pragma once

#include "tachi/sim/cloth.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <unordered_map>
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

/// An object model as a point cloud with a uniform hash grid for nearest-point queries.
class PointCloudCollider {
 public:
  /// `influence_m`: distance below which a particle is repelled; `stiffness`: acceleration (m/s^2)
  /// applied at zero distance, falling linearly to 0 at `influence_m` (seed 000: repulsion from distance).
  PointCloudCollider(std::vector<Eigen::Vector3f> points, float influence_m, float stiffness);

  /// Nearest object point within `influence_m` of p, if any.
  [[nodiscard]] std::optional<Eigen::Vector3f> nearest_within(const Eigen::Vector3f& p) const;
  /// Repulsive acceleration on a particle at p (zero outside the influence distance).
  [[nodiscard]] Eigen::Vector3f repulsion(const Eigen::Vector3f& p) const;
  [[nodiscard]] float influence() const { return influence_; }
  [[nodiscard]] const std::vector<Eigen::Vector3f>& points() const { return points_; }

 private:
  [[nodiscard]] std::int64_t key(int x, int y, int z) const;
  [[nodiscard]] Eigen::Vector3i cell_of(const Eigen::Vector3f& p) const;

  std::vector<Eigen::Vector3f> points_;
  float influence_;
  float stiffness_;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells_;
};

/// Everything the cloth collides with in one step. The hand is one of the spheres.
struct Colliders {
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
  std::optional<GroundPlane> ground;
  const PointCloudCollider* point_cloud = nullptr;  ///< not owned; may be null
  float thickness_m = 0.005F;                        ///< particles keep this far from surfaces
  float friction = 0.5F;  ///< 0..1: share of a touching particle's sliding that contact removes per sub-step
};

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
