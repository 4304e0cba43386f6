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

TEST(Render, TheHandMarkSitsAtItsProjectedPositionInAnOrbitedView) {
  View view;
  view.orbit(0.6f, 0.3f);
  Scene scene;
  scene.mesh = grid_cloth(11);
  const Eigen::Vector3f where(0.2f, -0.1f, 0.05f);
  scene.hand = Hand{where, HandState::Cutting, false};
  const cv::Mat image = render(scene, view);
  const cv::Point2f at_hand = to_pixel(view, where);
  EXPECT_TRUE(is(at(image, at_hand), kCuttingColour));
  // Turned away from the front, the point is no longer where a front view would put it.
  EXPECT_GT(cv::norm(at_hand - to_pixel(View{}, where)), 10.0);
}

TEST(Render, AFallenPieceIsDrawnWhereItFell) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11, {5});
  // The lower half (rows 6..10) dropped by 0.3 m.
  for (std::size_t i = 6 * 11; i < scene.mesh.positions.size(); ++i) scene.mesh.positions[i].y() -= 0.3f;
  const cv::Mat image = render(scene, view);
  EXPECT_TRUE(is(at(image, to_pixel(view, {0.0f, -0.15f, 0.0f})), kBackground)) << "where the piece hung";
  EXPECT_FALSE(is(at(image, to_pixel(view, {0.0f, -0.45f, 0.0f})), kBackground)) << "where it fell";
}

TEST(Render, HudShowsItsFigures) {
  View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  const cv::Mat bare = render(scene, view);
  scene.hud = Hud{};
  scene.hud->fps = 29.9;
  scene.hud->pieces = 2;
  const cv::Mat with_hud = render(scene, view);
  // Text is drawn in near-white, top left, and there is none without a HUD (the cloth is darker).
  const cv::Rect corner(0, 0, 300, 90);
  cv::Mat diff;
  cv::absdiff(bare(corner), with_hud(corner), diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1)), 200);
  cv::Mat text_pixels;
  const cv::Scalar bright(200, 200, 200), white(255, 255, 255);
  cv::inRange(with_hud(corner), bright, white, text_pixels);
  EXPECT_GT(cv::countNonZero(text_pixels), 50);
  cv::inRange(bare(corner), bright, white, text_pixels);
  EXPECT_EQ(cv::countNonZero(text_pixels), 0);
}

TEST(Render, ANewCutFlashesAndTheHeldParticleHasARing) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  scene.cut_particles = {60};
  scene.flash = 1.0f;
  scene.held_particle = 20;
  const cv::Mat image = render(scene, view);
  EXPECT_TRUE(is(at(image, to_pixel(view, scene.mesh.positions[60])), kFlashColour));
  const cv::Point2f held = to_pixel(view, scene.mesh.positions[20]);
  EXPECT_TRUE(is(at(image, held + cv::Point2f(9.0f, 0.0f)), kHeldColour));
  scene.flash = 0.0f;
  EXPECT_FALSE(is(at(render(scene, view), to_pixel(view, scene.mesh.positions[60])), kFlashColour));
}

TEST(Render, PickSurfaceFindsTheClothUnderThePixelAndNothingBesideIt) {
  View view;
  view.orbit(0.4f, -0.2f);
  Mesh mesh = grid_cloth(11);
  for (auto& p : mesh.positions) p.z() = 0.1f * p.x();  // tilted sheet
  const Eigen::Vector3f target = mesh.positions[5 * 11 + 3];
  const auto hit = pick_surface(mesh, view, to_pixel(view, target));
  ASSERT_TRUE(hit);
  EXPECT_LT((*hit - target).norm(), 1e-3f);
  EXPECT_FALSE(pick_surface(mesh, view, {2.0f, 2.0f}));
  const auto plane = pick_rest_plane(view, {2.0f, 2.0f});
  ASSERT_TRUE(plane);
  EXPECT_EQ(plane->z(), 0.0f);
  EXPECT_LT(cv::norm(to_pixel(view, *plane) - cv::Point2f(2.0f, 2.0f)), 0.5);
}

TEST(Render, GroupsOfAMeshGetDifferentShades) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  scene.mesh.groups.assign(scene.mesh.triangles.size(), 0);
  for (std::size_t t = scene.mesh.groups.size() / 2; t < scene.mesh.groups.size(); ++t) scene.mesh.groups[t] = 1;
  const cv::Mat image = render(scene, view);
  EXPECT_NE(at(image, to_pixel(view, {0.0f, 0.3f, 0.0f})), at(image, to_pixel(view, {0.0f, -0.3f, 0.0f})));
}

TEST(Render, HelpListsTheKeysOverTheImage) {
  const View view;
  Scene scene;
  scene.mesh = grid_cloth(11);
  const cv::Mat bare = render(scene, view);
  scene.show_help = true;
  const cv::Mat help = render(scene, view);
  // The list darkens the cloth behind it and writes bright text there.
  const cv::Point inside(view.width / 2, 60);
  EXPECT_LT(cv::sum(help.at<cv::Vec3b>(inside))[0], cv::sum(bare.at<cv::Vec3b>(inside))[0]);
  const cv::Rect list(view.width / 2 - 190, 40, 380, 20 * static_cast<int>(kKeyHelp.size()) + 20);
  cv::Mat text;
  cv::inRange(help(list), cv::Scalar(200, 200, 200), cv::Scalar(255, 255, 255), text);
  EXPECT_GT(cv::countNonZero(text), 500);
}
