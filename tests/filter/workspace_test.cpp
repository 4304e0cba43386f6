#include "tachi/filter/workspace.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace tachi::filter {
namespace {

// The user faces the sensor. In the camera frame (x right, y down, z forward as the camera sees it)
// the user's right hand is on the camera's left: x < 0. The mirror mapping puts it on the cloth's right.
TEST(WorkspaceMapping, DefaultIsAMirrorForAUserFacingTheSensor) {
  const WorkspaceMapping m = default_mapping();
  const Eigen::Vector3f users_right = m.to_world({-0.3F, 0.0F, 1.0F});
  EXPECT_NEAR(users_right.x(), 0.3F, 1e-6F);  // cloth's right
  const Eigen::Vector3f up = m.to_world({0.0F, -0.2F, 1.0F});
  EXPECT_NEAR(up.y(), 0.2F, 1e-6F);  // camera y down -> world y up
  const Eigen::Vector3f on_plane = m.to_world({0.1F, 0.1F, 1.0F});
  EXPECT_NEAR(on_plane.z(), 0.0F, 1e-6F);  // 1.0 m from the sensor lies on the cloth
  // The user stands on the cloth's +z side: pulling the hand back toward the body raises z,
  // pushing it toward the sensor (through the cloth) makes z negative.
  EXPECT_GT(m.to_world({0, 0, 1.2F}).z(), 0.0F);
  EXPECT_LT(m.to_world({0, 0, 0.9F}).z(), 0.0F);
  EXPECT_FALSE(validate(m).has_value());
}

TEST(WorkspaceMapping, ToCameraInvertsToWorld) {
  WorkspaceMapping m;
  m.rotation = Eigen::AngleAxisf(0.3F, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  m.translation_m = {0.1F, -0.2F, -1.1F};
  m.scale = 1.7F;
  const Eigen::Vector3f camera{0.25F, -0.1F, 1.3F};
  EXPECT_TRUE(m.to_camera(m.to_world(camera)).isApprox(camera, 1e-5F));
  // Scale multiplies distances in the world.
  const Eigen::Vector3f a = m.to_world({0, 0, 1}), b = m.to_world({0.1F, 0, 1});
  EXPECT_NEAR((a - b).norm(), 0.17F, 1e-5F);
}

TEST(WorkspaceMapping, ValidationRejectsReflectionsAndBadScale) {
  WorkspaceMapping m;
  m.rotation = Eigen::Vector3f{-1, 1, 1}.asDiagonal();  // a mirror by reflection, det -1
  EXPECT_TRUE(validate(m).has_value());
  m = {};
  m.rotation(0, 1) = 0.5F;
  EXPECT_TRUE(validate(m).has_value());
  m = {};
  m.scale = 0.0F;
  EXPECT_TRUE(validate(m).has_value());
}

}  // namespace
}  // namespace tachi::filter
