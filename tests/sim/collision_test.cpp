#include "tachi/sim/collision.hpp"
#include "tachi/sim/solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using namespace tachi::sim;

/// A free cloth lying horizontally (x-z plane) at height y.
Cloth horizontal_cloth(int n, float y) {
  ClothConfig c;
  c.columns = n;
  c.rows = n;
  c.pin = PinMode::None;
  Cloth cloth{c};
  for (auto& p : cloth.position) p = Eigen::Vector3f{p.x(), y, p.y()};
  return cloth;
}

TEST(Collision, ParticlesStayOutsideASphereTheClothDrapesOver) {
  Cloth cloth = horizontal_cloth(32, 0.4F);
  Colliders colliders;
  colliders.spheres.push_back({Eigen::Vector3f::Zero(), 0.3F});
  Solver solver;
  for (int s = 0; s < 180; ++s) {
    solver.step(cloth, colliders);
    for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
      ASSERT_GE(cloth.position[i].norm(), 0.3F + colliders.thickness_m - 1e-4F) << "particle " << i << " step " << s;
    }
  }
  // It draped: the middle rests on top of the sphere, the corners hang below its equator.
  EXPECT_NEAR(cloth.position[cloth.index(16, 16)].y(), 0.3F + colliders.thickness_m, 0.02F);
  EXPECT_LT(cloth.position[0].y(), 0.0F);
}

TEST(Collision, AMovingHandSpherePushesTheClothAway) {
  ClothConfig c;
  c.columns = 24;
  c.rows = 24;
  c.pin = PinMode::TopEdge;
  Cloth cloth{c};
  Colliders colliders;
  colliders.spheres.push_back({Eigen::Vector3f{0.0F, 0.0F, -0.2F}, 0.08F});
  Solver solver;
  for (int s = 0; s < 60; ++s) {
    colliders.spheres[0].centre.z() = -0.2F + 0.5F * static_cast<float>(s) / 60.0F;  // hand pushes through
    solver.step(cloth, colliders);
    for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
      ASSERT_GE((cloth.position[i] - colliders.spheres[0].centre).norm(), 0.08F + colliders.thickness_m - 1e-4F);
    }
  }
  EXPECT_GT(cloth.position[cloth.index(12, 12)].z(), 0.1F);  // the cloth was carried forward
}

TEST(Collision, ClothFallsOntoTheGroundAndABoxWithoutEnteringThem) {
  Cloth cloth = horizontal_cloth(24, 0.5F);
  Colliders colliders;
  colliders.ground = GroundPlane{-0.5F};
  colliders.boxes.push_back({Eigen::Vector3f{0.0F, -0.4F, 0.0F}, Eigen::Vector3f{0.2F, 0.1F, 0.2F}});
  Solver solver;
  for (int s = 0; s < 120; ++s) solver.step(cloth, colliders);
  for (const auto& p : cloth.position) {
    EXPECT_GE(p.y(), -0.5F + colliders.thickness_m - 1e-4F);
    const Eigen::Vector3f local = (p - colliders.boxes[0].centre).cwiseAbs();
    EXPECT_FALSE((local.array() < colliders.boxes[0].half_extent.array()).all()) << p.transpose();
  }
  // The middle rests on the box top, the corners on the ground.
  EXPECT_NEAR(cloth.position[cloth.index(12, 12)].y(), -0.3F + colliders.thickness_m, 0.02F);
  EXPECT_NEAR(cloth.position[0].y(), -0.5F + colliders.thickness_m, 0.02F);
}

TEST(Collision, BoxProjectionLeavesAlongTheShallowestAxis) {
  const Box box{Eigen::Vector3f::Zero(), Eigen::Vector3f{1.0F, 1.0F, 1.0F}};
  Eigen::Vector3f p{0.2F, 0.9F, -0.1F};
  EXPECT_TRUE(project_out_of_box(p, box, 0.0F));
  EXPECT_FLOAT_EQ(p.y(), 1.0F);
  EXPECT_FLOAT_EQ(p.x(), 0.2F);
  Eigen::Vector3f outside{2.0F, 0.0F, 0.0F};
  EXPECT_FALSE(project_out_of_box(outside, box, 0.0F));
}

TEST(Collision, NonFiniteCollidersLeaveTheClothUntouched) {
  ClothConfig c;
  c.columns = 8;
  c.rows = 8;
  Cloth cloth{c};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Colliders colliders;
  colliders.spheres.push_back({Eigen::Vector3f{nan, 0.0F, 0.0F}, 0.3F});
  colliders.spheres.push_back({Eigen::Vector3f::Zero(), nan});
  colliders.boxes.push_back({Eigen::Vector3f{0.0F, nan, 0.0F}, Eigen::Vector3f::Constant(0.2F)});
  colliders.ground = GroundPlane{nan};
  Solver solver;
  for (int s = 0; s < 10; ++s) solver.step(cloth, colliders);
  for (const auto& p : cloth.position) ASSERT_TRUE(p.allFinite());
}

TEST(Collision, PointCloudNearestPointMatchesBruteForce) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 500; ++i) {
    const float t = static_cast<float>(i);
    points.emplace_back(std::sin(t * 1.7F) * 0.5F, std::cos(t * 0.37F) * 0.5F, std::sin(t * 0.11F) * 0.5F);
  }
  points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);  // a bad sample is ignored
  const PointCloudCollider cloud{points, 0.1F, 50.0F};
  for (int q = 0; q < 200; ++q) {
    const float t = static_cast<float>(q) * 0.013F;
    const Eigen::Vector3f p{std::sin(t * 5.0F) * 0.5F, std::cos(t * 3.0F) * 0.5F, std::sin(t * 7.0F) * 0.5F};
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i + 1 < points.size(); ++i) best = std::min(best, (points[i] - p).norm());
    const auto found = cloud.nearest_within(p);
    if (best < 0.1F) {
      ASSERT_TRUE(found.has_value());
      EXPECT_NEAR((*found - p).norm(), best, 1e-6F);
    } else {
      EXPECT_FALSE(found.has_value());
    }
  }
}

TEST(Collision, PointCloudRepulsionHoldsAFallingClothUp) {
  // Seed 000: the object is a point cloud; particles near it are pushed away from the nearest point.
  std::vector<Eigen::Vector3f> table;
  for (int i = -30; i <= 30; ++i) {
    for (int k = -30; k <= 30; ++k) table.emplace_back(0.02F * static_cast<float>(i), 0.0F, 0.02F * static_cast<float>(k));
  }
  const PointCloudCollider cloud{table, 0.05F, 400.0F};
  EXPECT_GT(cloud.repulsion(Eigen::Vector3f{0.0F, 0.01F, 0.0F}).y(), 0.0F);
  EXPECT_EQ(cloud.repulsion(Eigen::Vector3f{0.0F, 0.2F, 0.0F}), Eigen::Vector3f::Zero());

  Cloth with = horizontal_cloth(16, 0.2F);
  Cloth without = with;
  for (auto* cloth : {&with, &without}) {
    for (auto& p : cloth->position) p *= 0.5F;  // half-size cloth, inside the table
  }
  Colliders colliders;
  colliders.point_cloud = &cloud;
  Solver a, b;
  for (int s = 0; s < 120; ++s) {
    a.step(with, colliders);
    b.step(without);
  }
  EXPECT_GT(with.position[with.index(8, 8)].y(), 0.0F);      // held above the table
  EXPECT_LT(without.position[without.index(8, 8)].y(), -1.0F);  // fell through where there is none
}

}  // namespace
