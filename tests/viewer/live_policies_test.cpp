// The live viewer's policies without a window or a bus: frames at --fps, video frames in real time, the held
// mouse blade, the missing-cloth warning, --duration / --exit-when-idle, the mouse, and the offline mesh view.
#include "tachi/viewer/live_policies.hpp"
#include "tachi/viewer/node.hpp"
#include "tachi/viewer/outputs.hpp"

#include "square_mesh.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

using namespace tachi::viewer;
using namespace std::chrono_literals;

namespace {
using test::square;
MouseEvent event(MouseEvent::Kind kind, cv::Point2f pixel, bool shift = false) { return {kind, pixel, 0, shift}; }

// A window that shows nothing and answers with a scripted key: the mesh view's loop without a display.
class ScriptedWindow final : public ViewerWindow {
 public:
  explicit ScriptedWindow(std::vector<int> keys) : keys_(std::move(keys)) {}
  cv::Size image_size() const override { return {96, 64}; }
  void show(const cv::Mat& image) override { shown.push_back(image.clone()); }
  int poll(int) override {
    if (keys_.empty()) return -1;
    const int key = keys_.front();
    keys_.erase(keys_.begin());
    return key;
  }
  std::vector<MouseEvent> take_mouse_events() override { return {}; }
  bool open() const override { return true; }
  void hide_pointer() override {}
  std::vector<cv::Mat> shown;

 private:
  std::vector<int> keys_;
};

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("tachi_viewer_policies_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}
}  // namespace

TEST(FrameSchedule, RendersOncePerSlotAndStartsAgainWhenFarBehind) {
  const auto t0 = Clock::time_point{} + 1h;
  FrameSchedule frames{10.0, t0};  // 100 ms slots
  EXPECT_TRUE(frames.due(t0));
  EXPECT_FALSE(frames.due(t0 + 50ms)) << "the next slot is at 100 ms";
  EXPECT_EQ(frames.wait(t0 + 50ms), Clock::duration(50ms));
  EXPECT_TRUE(frames.due(t0 + 100ms));
  // Two slots late: both are rendered, one per call, to keep the rate.
  EXPECT_TRUE(frames.due(t0 + 320ms));
  EXPECT_TRUE(frames.due(t0 + 320ms));
  EXPECT_FALSE(frames.due(t0 + 320ms));
  // More than five frames behind (a stalled machine): from now on, not a burst of catch-up frames.
  EXPECT_TRUE(frames.due(t0 + 2s));
  EXPECT_FALSE(frames.due(t0 + 2s));
  EXPECT_TRUE(frames.due(t0 + 2s + 100ms));
}

TEST(FrameSchedule, WaitsAtLeastOneMillisecondAndAtMostOneTenthOfASecond) {
  const auto t0 = Clock::time_point{} + 1h;
  FrameSchedule slow{1.0, t0};
  slow.due(t0);
  EXPECT_EQ(slow.wait(t0), Clock::duration(100ms)) << "a stop request is seen within 100 ms even at --fps 1";
  EXPECT_EQ(slow.wait(t0 + 5s), Clock::duration(1ms)) << "a late frame still waits a little: no spinning";
}

TEST(VideoFrames, AVideoPlaysAtTheSpeedTheRunWentWhateverTheRenderRate) {
  EXPECT_EQ(video_frames_due(0.0, 30.0), 1U);
  EXPECT_EQ(video_frames_due(1.0 / 30.0, 30.0), 2U) << "a frame shown at its slot counts";
  EXPECT_EQ(video_frames_due(0.02, 30.0), 1U) << "shown before its slot: waits for the next call";
  EXPECT_EQ(video_frames_due(1.0, 30.0), 31U) << "a viewer rendering at 1 fps still fills 30 frames a second";
  EXPECT_EQ(video_frames_due(-0.5, 30.0), 1U);
}

TEST(BladeHold, RepeatsAHeldBladeEveryQuarterSecond) {
  const auto t0 = Clock::time_point{} + 1h;
  BladeHold hold{t0};
  EXPECT_FALSE(hold.due(t0 + 250ms));
  EXPECT_TRUE(hold.due(t0 + 251ms));
  hold.sent(t0 + 300ms);
  EXPECT_FALSE(hold.due(t0 + 500ms));
  EXPECT_TRUE(hold.due(t0 + 600ms));
}

TEST(ClothWatch, WarnsOnTheHudAfterThreeSecondsAndInTheLogEveryFive) {
  const auto t0 = Clock::time_point{} + 1h;
  ClothWatch watch{42, t0};
  EXPECT_EQ(watch.warning(t0 + 3s), "");
  EXPECT_FALSE(watch.log_due(t0 + 3s));
  EXPECT_EQ(watch.warning(t0 + 4s), "no cloth state for 4 s: is tachi-sim running on domain 42?");
  EXPECT_TRUE(watch.log_due(t0 + 4s)) << "said in the log as soon as the HUD says it";
  EXPECT_FALSE(watch.log_due(t0 + 8s));
  EXPECT_TRUE(watch.log_due(t0 + 9s + 1ms));
  watch.state_arrived(t0 + 10s);
  EXPECT_EQ(watch.warning(t0 + 11s), "");
  EXPECT_FALSE(watch.log_due(t0 + 12s)) << "5 s after the last log line, but the cloth came back 2 s ago";
  EXPECT_TRUE(watch.log_due(t0 + 15s)) << "gone again for 5 s, and 6 s since the last log line";
  EXPECT_EQ(watch.without_state(t0 + 11s), Clock::duration(1s));
}

TEST(RunLimits, DurationAndIdleAfterTheFirstStateEndTheRun) {
  EXPECT_FALSE((RunLimits{0.0, 0.0}.over(1h, 5, 1h))) << "0: run until stopped";
  EXPECT_FALSE((RunLimits{2.0, 0.0}.over(2s, 0, 0s)));
  EXPECT_TRUE((RunLimits{2.0, 0.0}.over(2s + 1ms, 0, 0s)));
  const RunLimits idle{0.0, 1.5};
  EXPECT_FALSE(idle.over(1h, 0, 1h)) << "a viewer started before the simulator waits for its first state";
  EXPECT_FALSE(idle.over(1h, 3, 1s));
  EXPECT_TRUE(idle.over(1h, 3, 2s));
}

TEST(MouseControl, TheBladeCutsWithTheLeftButtonHoldsAndClosesTheStroke) {
  const Mesh mesh = square();
  View view;
  MouseControl mouse{true};
  EXPECT_FALSE(mouse.cursor()) << "no cursor before the mouse moved";
  EXPECT_FALSE(mouse.on_event(event(MouseEvent::Move, to_pixel(view, {0.0F, 0.0F, 0.0F})), mesh, view));
  EXPECT_EQ(mouse.label(), "(mouse)");
  const auto press = mouse.on_event(event(MouseEvent::LeftDown, to_pixel(view, {-0.2F, 0.0F, 0.0F})), mesh, view);
  ASSERT_TRUE(press);
  EXPECT_TRUE(press->cutting);
  EXPECT_EQ(mouse.label(), "(mouse, cutting)");
  ASSERT_TRUE(mouse.cursor());
  EXPECT_TRUE(mouse.cursor()->cutting);
  const auto held = mouse.hold(mesh, view);
  ASSERT_TRUE(held) << "held still: the same spot again";
  EXPECT_LT((held->position_m - press->position_m).norm(), 1e-4F);
  EXPECT_EQ(mouse.samples(), 2U);
  const auto last = mouse.finish(mesh, view);
  ASSERT_TRUE(last) << "stopping mid-stroke closes it";
  EXPECT_FALSE(last->cutting);
  EXPECT_EQ(last->stroke_id, press->stroke_id);
  EXPECT_FALSE(mouse.hold(mesh, view)) << "released: nothing to hold";
  EXPECT_FALSE(mouse.finish(mesh, view));
  EXPECT_EQ(mouse.samples(), 3U);
}

TEST(MouseControl, WithoutTheBladeTheMouseOrbitsPansAndZooms) {
  const Mesh mesh = square();
  const View home;
  View view = home;
  MouseControl mouse{false};
  EXPECT_FALSE(mouse.on_event(event(MouseEvent::LeftDown, {100.0F, 100.0F}), mesh, view));
  EXPECT_FALSE(mouse.on_event(event(MouseEvent::Move, {140.0F, 100.0F}), mesh, view));
  EXPECT_NE(view.yaw_rad, home.yaw_rad) << "left drag orbits";
  mouse.on_event(event(MouseEvent::LeftUp, {140.0F, 100.0F}), mesh, view);
  const auto centre = view.centre;
  mouse.on_event(event(MouseEvent::RightDown, {140.0F, 100.0F}, true), mesh, view);
  mouse.on_event(event(MouseEvent::Move, {180.0F, 130.0F}), mesh, view);
  EXPECT_NE(view.centre, centre) << "shift + right drag pans";
  mouse.on_event(event(MouseEvent::RightUp, {180.0F, 130.0F}), mesh, view);
  const float across = view.metres_across;
  MouseEvent wheel = event(MouseEvent::Wheel, {180.0F, 130.0F});
  wheel.wheel = 1;
  mouse.on_event(wheel, mesh, view);
  EXPECT_LT(view.metres_across, across) << "the wheel away from the user zooms in";
  EXPECT_FALSE(mouse.cursor());
  EXPECT_EQ(mouse.label(), "");
  EXPECT_EQ(mouse.samples(), 0U);
}

TEST(Outputs, FramesDirGetsEveryFrameAndTheSnapshotKeyNumbersItsFiles) {
  const auto dir = scratch("outputs");
  ViewerOptions options;
  options.frames_dir = (dir / "frames").string();
  options.snapshot_dir = (dir / "snaps").string();
  options.snapshot = (dir / "last.png").string();
  Outputs outputs{options, {32, 24}};
  EXPECT_TRUE(outputs.any());
  outputs.snapshot_now();
  EXPECT_FALSE(std::filesystem::exists(options.snapshot_dir)) << "no frame yet: no snapshot";
  const cv::Mat red(24, 32, CV_8UC3, cv::Scalar(0, 0, 255));
  outputs.frame(red, Clock::now());
  outputs.frame(red, Clock::now());
  outputs.snapshot_now();
  outputs.snapshot_now();
  outputs.finish(red);
  EXPECT_TRUE(std::filesystem::exists(dir / "frames" / "frame_00000.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "frames" / "frame_00001.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "snaps" / "tachi_snapshot_2.png"));
  const cv::Mat last = cv::imread(options.snapshot);
  ASSERT_FALSE(last.empty());
  EXPECT_EQ(last.size(), red.size());
  std::filesystem::remove_all(dir);
}

TEST(MeshView, ShowsTheMeshUntilQAndWritesTheSnapshot) {
  const auto dir = scratch("mesh");
  std::ofstream(dir / "cloth.obj") << "v -0.5 0.5 0\nv 0.5 0.5 0\nv -0.5 -0.5 0\nv 0.5 -0.5 0\nf 1 2 3\nf 2 4 3\n";
  ViewerOptions options;
  options.mesh = (dir / "cloth.obj").string();
  options.snapshot = (dir / "mesh.png").string();
  options.fps = 240.0;
  ScriptedWindow window{{-1, 'q'}};
  MeshView view{options, &window};
  EXPECT_TRUE(view.spin_once());
  EXPECT_FALSE(view.spin_once()) << "q quits";
  EXPECT_EQ(view.finish(), 0);
  ASSERT_EQ(window.shown.size(), 2U);
  EXPECT_EQ(window.shown.back().size(), cv::Size(96, 64)) << "rendered at the window's size";
  EXPECT_EQ(cv::imread(options.snapshot).size(), cv::Size(96, 64));

  options.snapshot = (dir / "headless.png").string();
  MeshView headless{options, nullptr};
  EXPECT_FALSE(headless.spin_once()) << "headless: straight to the snapshot";
  EXPECT_EQ(headless.finish(), 0);
  EXPECT_EQ(cv::imread(options.snapshot).size(), cv::Size(options.size, options.size));

  options.mesh = (dir / "missing.obj").string();
  EXPECT_THROW((MeshView{options, nullptr}), std::runtime_error);
  std::filesystem::remove_all(dir);
}
