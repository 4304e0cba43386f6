#include "tachi/viewer/controls.hpp"
#include "tachi/viewer/frame_stats.hpp"
#include "tachi/viewer/mesh_file.hpp"

#include "square_mesh.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace tachi::viewer;

namespace {
using test::square;

std::filesystem::path write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".obj");
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(Controls, KeysOrbitPanZoomResetAndAskForHelpSnapshotQuit) {
  const View home;
  View view = home;
  EXPECT_EQ(on_key('h', view, home), KeyAction::ToggleHelp);
  EXPECT_EQ(on_key('p', view, home), KeyAction::Snapshot);
  EXPECT_EQ(on_key('q', view, home), KeyAction::Quit);
  EXPECT_EQ(on_key(27, view, home), KeyAction::Quit);
  EXPECT_EQ(on_key('d', view, home), KeyAction::ViewChanged);
  EXPECT_GT(view.yaw_rad, 0.0f);
  EXPECT_EQ(on_key(0xff52, view, home), KeyAction::ViewChanged);  // up arrow (X11)
  EXPECT_LT(view.pitch_rad, 0.0f);
  on_key('+', view, home);
  EXPECT_LT(view.metres_across, home.metres_across);
  on_key('l', view, home);
  on_key('r', view, home);
  EXPECT_EQ(view.yaw_rad, home.yaw_rad);
  EXPECT_EQ(view.metres_across, home.metres_across);
  EXPECT_EQ(view.centre, home.centre);
  EXPECT_EQ(on_key('z', view, home), KeyAction::None);
}

TEST(MouseBlade, PressDragReleaseMakesOneStrokeOnTheClothSurface) {
  const Mesh mesh = square();
  const View view;
  MouseBlade blade;
  EXPECT_FALSE(blade.move(mesh, view, {400.0f, 400.0f})) << "no button: no sample";
  const auto first = blade.press(mesh, view, to_pixel(view, {-0.2f, 0.1f, 0.0f}));
  ASSERT_TRUE(first);
  EXPECT_TRUE(first->cutting);
  EXPECT_FALSE(first->outside_cloth);
  EXPECT_LT((first->position_m - Eigen::Vector3f(-0.2f, 0.1f, 0.0f)).norm(), 0.01f);
  const auto off = blade.move(mesh, view, to_pixel(view, {0.7f, 0.1f, 0.0f}));
  ASSERT_TRUE(off);
  EXPECT_TRUE(off->outside_cloth) << "beyond the edge the spot lies on the rest plane";
  EXPECT_NEAR(off->position_m.x(), 0.7f, 0.01f);
  const auto last = blade.release(mesh, view, to_pixel(view, {0.7f, 0.1f, 0.0f}));
  ASSERT_TRUE(last);
  EXPECT_FALSE(last->cutting);
  EXPECT_EQ(first->stroke_id, last->stroke_id);
  EXPECT_EQ(blade.press(mesh, view, {400.0f, 400.0f})->stroke_id, first->stroke_id + 1);
}

TEST(MeshFile, ReadsGroupsAsPiecesAndPolygonsAsFans) {
  const auto path = write_file("groups", "# two pieces\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 -2 0\nv 1 -2 0\n"
                                         "vt 0 0\ng piece_0\nf 1/1 2/1 3/1 4/1\ng piece_1\nf -1 -2 1\n");
  std::string error;
  const auto mesh = read_obj(path, error);
  ASSERT_TRUE(mesh) << error;
  EXPECT_EQ(mesh->positions.size(), 6u);
  ASSERT_EQ(mesh->triangles.size(), 3u);
  EXPECT_EQ(mesh->groups, (std::vector<std::uint16_t>{0, 0, 1}));
  EXPECT_EQ(mesh->triangles[2], (std::array<std::uint32_t, 3>{5, 4, 0}));
  std::filesystem::remove(path);
}

TEST(MeshFile, BadFilesAreRefusedWithTheFileAndLine) {
  std::string error;
  const auto bad_index = write_file("bad_index", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  EXPECT_FALSE(read_obj(bad_index, error));
  EXPECT_NE(error.find(bad_index.string() + ":3"), std::string::npos) << error;
  const auto nan = write_file("nan", "v 0 nan 0\n");
  EXPECT_FALSE(read_obj(nan, error));
  EXPECT_NE(error.find(":1: non-finite"), std::string::npos) << error;
  const auto empty = write_file("empty", "v 0 0 0\n");
  EXPECT_FALSE(read_obj(empty, error));
  EXPECT_FALSE(read_obj("/nonexistent/cloth.obj", error));
  for (const auto& p : {bad_index, nan, empty}) std::filesystem::remove(p);
}

TEST(MeshFile, FramingShowsTheHangingClothNotAPieceFarBelow) {
  Mesh mesh = square();
  mesh.positions.push_back({0.0f, -500.0f, 0.0f});
  const View view = framing(mesh, View{});
  EXPECT_NEAR(view.centre.y(), 0.0f, 1e-4f);
  EXPECT_LT(view.metres_across, 2.0f);
}

TEST(FrameStats, CountsFramesPerSecondAndQuantilesOfTheStateAge) {
  FrameStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i <= 30; ++i) stats.frame(t0 + std::chrono::milliseconds(i * 20), i == 30 ? 100.0 : 10.0);
  EXPECT_NEAR(stats.fps(), 50.0, 0.5);
  EXPECT_DOUBLE_EQ(*stats.age_ms(0.5), 10.0);
  EXPECT_DOUBLE_EQ(*stats.age_ms(1.0), 100.0);
}

// The HUD's "state age" is the newest hand sample's capture -> picture delay, measured when it was first
// shown; while the hand rests (frames with no new sample) it holds, instead of climbing to 30 s.
TEST(FrameStats, TheHudsStateAgeHoldsWhileNoNewSampleComes) {
  FrameStats stats;
  EXPECT_FALSE(stats.latest_age_ms());
  const auto t0 = std::chrono::steady_clock::now();
  stats.frame(t0, 12.0);
  stats.frame(t0 + std::chrono::milliseconds(33), 15.0);
  for (int i = 2; i < 900; ++i) stats.frame(t0 + std::chrono::milliseconds(33 * i), std::nullopt);  // 30 s idle
  ASSERT_TRUE(stats.latest_age_ms());
  EXPECT_DOUBLE_EQ(*stats.latest_age_ms(), 15.0);
}
