#include "tachi/filter/cloth_proximity.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace tachi::filter {
namespace {

TEST(ClothProximity, RestClothDistanceIsTheHeightAboveThePlane) {
  const ClothProximityParams p;
  const Proximity in_front = proximity_to_rest_cloth({0.1F, 0.2F, 0.07F}, p);
  EXPECT_NEAR(in_front.distance_m, 0.07F, 1e-6F);
  EXPECT_FALSE(in_front.outside);
}

TEST(ClothProximity, RestClothOutsideMeasuresToTheEdge) {
  const ClothProximityParams p;  // 1 m x 1 m
  const Proximity beside = proximity_to_rest_cloth({0.8F, 0.0F, 0.0F}, p);
  EXPECT_TRUE(beside.outside);
  EXPECT_NEAR(beside.distance_m, 0.3F, 1e-6F);
  EXPECT_TRUE(proximity_to_rest_cloth({0.0F, -0.51F, 0.2F}, p).outside);
}

TEST(ClothProximity, PushingThroughTheClothCountsAsContact) {
  ClothProximityParams p;
  EXPECT_EQ(proximity_to_rest_cloth({0.0F, 0.0F, -0.2F}, p).distance_m, 0.0F);
  p.behind_cloth_is_contact = false;
  EXPECT_NEAR(proximity_to_rest_cloth({0.0F, 0.0F, -0.2F}, p).distance_m, 0.2F, 1e-6F);
}

TEST(ClothProximity, ParticlesGiveTheNearestOne) {
  const ClothProximityParams p;
  const std::vector<float> xyz{0, 0, 0, 0.1F, 0, 0.05F, 0.2F, 0, 0};
  const auto near = proximity_to_particles({0.1F, 0.0F, 0.15F}, xyz, p);
  ASSERT_TRUE(near.has_value());
  EXPECT_NEAR(near->distance_m, 0.10F, 1e-6F);
  EXPECT_TRUE(near->nearest.isApprox(Eigen::Vector3f(0.1F, 0, 0.05F)));
  EXPECT_FALSE(near->outside);
  const auto away = proximity_to_particles({0.5F, 0.0F, 0.0F}, xyz, p);
  ASSERT_TRUE(away.has_value());
  EXPECT_TRUE(away->outside);  // 0.3 m from the nearest particle in the cloth plane
  EXPECT_FALSE(proximity_to_particles({0, 0, 0}, {}, p).has_value());
  const std::vector<float> broken{std::nanf(""), 0, 0};
  EXPECT_FALSE(proximity_to_particles({0, 0, 0}, broken, p).has_value());
}

}  // namespace
}  // namespace tachi::filter
