#include "tachi/viewer/render.hpp"

#include <gtest/gtest.h>

#include <limits>

using namespace tachi::viewer;

namespace {
// A flat n x n grid cloth of 1 m x 1 m in z = 0, two triangles per cell; rows in `skip_rows` have
// no triangles (a horizontal cut).
Mesh grid_cloth(int n, std::vector<int> skip_rows = {}) {
  Mesh mesh;
  for (int v = 0; v < n; ++v)
    for (int u = 0; u < n; ++u)
      mesh.positions.emplace_back(-0.5f + static_cast<float>(u) / static_cast<float>(n - 1),
                                  0.5f - static_cast<float>(v) / static_cast<float>(n - 1), 0.0f);
  for (int v = 0; v + 1 < n; ++v) {
    if (std::find(skip_rows.begin(), skip_rows.end(), v) != skip_rows.end()) continue;
    for (int u = 0; u + 1 < n; ++u) {
      const auto i = static_cast<std::uint32_t>(v * n + u);
      const auto w = static_cast<std::uint32_t>(n);
      mesh.triangles.push_back({i, i + 1, i + w});
      mesh.triangles.push_back({i + 1, i + w + 1, i + w});
    }
  }
  return mesh;
}

cv::Vec3b at(const cv::Mat& image, const cv::Point2f& p) { return image.at<cv::Vec3b>(cv::Point(p)); }
bool is(const cv::Vec3b& pixel, const cv::Scalar& colour) {
  return pixel == cv::Vec3b(static_cast<uchar>(colour[0]), static_cast<uchar>(colour[1]), static_cast<uchar>(colour[2]));
}
}  // namespace

TEST(Render, DrawsTheClothWhereItHangsAndBackgroundAroundIt) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  const cv::Mat image = render(scene, view);
  ASSERT_EQ(image.size(), cv::Size(view.width, view.height));
  EXPECT_FALSE(is(at(image, to_pixel(view, {0.1f, 0.1f, 0.0f})), kBackground));
  EXPECT_TRUE(is(at(image, to_pixel(view, {0.7f, 0.1f, 0.0f})), kBackground));
  EXPECT_TRUE(is(at(image, to_pixel(view, {0.0f, 0.62f, 0.0f})), kBackground));
}

TEST(Render, HandMarkIsBlueIdleGreenCuttingRedOutside) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  const Eigen::Vector3f where(0.2f, -0.1f, 0.0f);
  scene.hand = Hand{where, HandState::Idle, false};
  EXPECT_TRUE(is(at(render(scene, view), to_pixel(view, where)), kIdleColour));
  scene.hand->state = HandState::Cutting;
  EXPECT_TRUE(is(at(render(scene, view), to_pixel(view, where)), kCuttingColour));
  scene.hand->outside_cloth = true;
  EXPECT_TRUE(is(at(render(scene, view), to_pixel(view, where)), kOutsideColour));
}

TEST(Render, ACutShowsAsAGapInTheCloth) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11, {5});  // the row of cells between y = 0.0 and y = -0.1 is cut away
  const cv::Mat image = render(scene, view);
  EXPECT_TRUE(is(at(image, to_pixel(view, {0.03f, -0.05f, 0.0f})), kBackground));
  EXPECT_FALSE(is(at(image, to_pixel(view, {0.03f, 0.05f, 0.0f})), kBackground));
  EXPECT_FALSE(is(at(image, to_pixel(view, {0.03f, -0.15f, 0.0f})), kBackground));
}

TEST(Render, SkipsNonFiniteAndOutOfRangeGeometry) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(5);
  scene.mesh.positions[6] = {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f};
  scene.mesh.triangles.push_back({0, 1, 999});
  scene.hand = Hand{{std::numeric_limits<float>::infinity(), 0.0f, 0.0f}, HandState::Cutting, false};
  scene.stroke = {{0.0f, 0.0f, 0.0f}, {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f}, {0.2f, 0.2f, 0.0f}};
  const cv::Mat image = render(scene, view);
  EXPECT_EQ(image.size(), cv::Size(view.width, view.height));
}
