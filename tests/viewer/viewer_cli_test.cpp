// tachi-viewer as a process, headless: flags refused by name, the offline mesh view, the warnings of a
// viewer that writes nothing or sees no cloth, a video of a live simulator, a killed viewer's video, and
// bad inputs replayed over DDS while the real cloth stays on screen. Domain ids 150-154 (docs/testing.md).
#include "viewer_process.hpp"
#include "node_status.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <csignal>
#include <fstream>
#include <limits>
#include <thread>

using namespace std::chrono_literals;
namespace bus = tachi::bus;
using tachi::test::ChildProcess;

namespace {
const cv::Vec3b kBackground = background_pixel();

}  // namespace

TEST(ViewerCli, NonFiniteAndBadFlagsAreRefusedNamingTheFlag) {
  for (const auto& [flag, value] : std::vector<std::pair<std::string, std::string>>{
           {"--fps", "nan"}, {"--fps", "inf"}, {"--duration", "nan"}, {"--exit-when-idle", "-1"}, {"--video", "out.mkv"}}) {
    const auto r = tachi::test::run({kViewer, "--headless", flag, value}, 10s);
    EXPECT_EQ(r.exit_code, 2) << flag << ' ' << value;
    EXPECT_NE(r.err.find(flag), std::string::npos) << r.err;
  }
  const auto r = tachi::test::run({kViewer, "--headless", "--mouse"}, 10s);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--mouse"), std::string::npos) << r.err;
}

TEST(ViewerCli, MeshViewRendersAnObjWithItsPiecesInDifferentShades) {
  const tachi::test::ScratchDir dir{"viewer_mesh"};
  {
    // Two pieces: the upper half of the 1 m cloth hanging, the lower one fallen 0.2 m.
    std::ofstream obj(dir / "cloth.obj");
    obj << "v -0.5 0.5 0\nv 0.5 0.5 0\nv -0.5 0 0\nv 0.5 0 0\n"
           "v -0.5 -0.2 0\nv 0.5 -0.2 0\nv -0.5 -0.7 0\nv 0.5 -0.7 0\n"
           "g piece_0\nf 1 3 2\nf 2 3 4\ng piece_1\nf 5 7 6\nf 6 7 8\n";
  }
  const auto png = (dir / "view.png").string();
  const auto r = tachi::test::run({kViewer, "--mesh", (dir / "cloth.obj").string(), "--headless", "--snapshot", png,
                                   "--size", "400"}, 20s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat image = cv::imread(png);
  ASSERT_EQ(image.size(), cv::Size(400, 400));
  // The view frames the mesh: its centre (0, -0.1) is mid-image; 1.2 m tall fills 1/1.2 of it.
  const cv::Vec3b upper = image.at<cv::Vec3b>(100, 200), lower = image.at<cv::Vec3b>(300, 200);
  EXPECT_NE(upper, kBackground);
  EXPECT_NE(lower, kBackground);
  EXPECT_NE(upper, lower) << "each piece has its own shade";
  EXPECT_EQ(image.at<cv::Vec3b>(200, 200), kBackground) << "the gap between the pieces";

  const auto bad = tachi::test::run({kViewer, "--mesh", (dir / "missing.obj").string(), "--headless"}, 10s);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--mesh"), std::string::npos) << bad.err;
}

TEST(ViewerCli, MeshViewReadsWhatTachiSimExports) {
  const tachi::test::ScratchDir dir{"viewer_sim_mesh"};
  {
    // A full-width stroke at y = -0.1 m cuts off the lower piece, which falls for 120 steps (2 s).
    std::ofstream stroke(dir / "stroke.csv");
    stroke << "t,x,y,z\n";
    for (int i = 0; i <= 60; ++i) stroke << 0.2 + i / 60.0 << ',' << -0.6 + 1.2 * i / 60.0 << ",-0.1,0.01\n";
  }
  const auto sim = tachi::test::run({kSim, "--offline", "--grid", "32", "--pin", "top-edge", "--stroke",
                                     (dir / "stroke.csv").string(), "--steps", "120", "--export", (dir / "out").string()}, 60s);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto png = (dir / "view.png").string();
  const auto r = tachi::test::run({kViewer, "--mesh", (dir / "out" / "cloth.obj").string(), "--headless", "--snapshot", png,
                                   "--size", "400"}, 20s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat image = cv::imread(png);
  ASSERT_EQ(image.size(), cv::Size(400, 400));
  // Framed on what hangs (the upper piece, y from 0.5 down to about -0.1): cloth in the middle, the
  // background at the image's corners.
  EXPECT_NE(image.at<cv::Vec3b>(200, 200), kBackground);
  EXPECT_EQ(image.at<cv::Vec3b>(5, 5), kBackground);
}

TEST(ViewerCli, HeadlessSaysWhenItWritesNothingAndWhileNoClothArrives) {
  const auto r = tachi::test::run({kViewer, "--headless", "--domain", "150", "--duration", "4"}, 20s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("nothing will be written"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no cloth state for 3 s"), std::string::npos) << r.err;
}

TEST(ViewerCli, BadInputsAreRejectedAndTheVideoKeepsShowingTheRealCloth) {
  constexpr unsigned kDomain = 151;
  const tachi::test::ScratchDir dir{"viewer_bad_inputs"};
  const auto video = (dir / "view.avi").string();
  const auto png = (dir / "last.png").string();
  // The simulator runs until the test stops it (SIGINT at the end): with --duration 12 it stopped publishing
  // before the test's last checks when a loaded machine stretched them past 12 s (failed once in 23.7 s under
  // a full ctest beside two evaluations), and the video's last second then showed no live cloth.
  ChildProcess sim({kSim, "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain), "--duration", "90"});
  ChildProcess viewer({kViewer, "--headless", "--domain", std::to_string(kDomain), "--video", video, "--snapshot", png,
                       "--size", "320", "--fps", "20", "--duration", "60"});
  bus::Participant dds{kDomain};
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  bus::Writer<tachi_msg_ClothTopology> bad_topology{dds, bus::topics::cloth_topology};
  bus::Writer<tachi_msg_ClothState> bad_state{dds, bus::topics::cloth_state};
  ASSERT_TRUE(topologies.wait_for_data(20s)) << sim.err();
  const auto real = topologies.take();
  ASSERT_FALSE(real.empty());
  const tachi_msg_ClothTopology& t = *real.back();
  ASSERT_TRUE(bad_state.wait_for_readers(1, 20s)) << viewer.err();
  // The viewer has the real cloth: its heartbeat no longer says it waits for one, and it has drawn it.
  ASSERT_TRUE(tachi::test::wait_for_status(status, "tachi-viewer", [](const tachi_msg_NodeStatus& s) {
    return std::string(s.detail).empty() && tachi::test::metric(s, "frames").value_or(0) > 0;
  }, 20s)) << viewer.err();
  // Each bad topology is written once its predecessor was counted: the topic keeps only the last one.
  std::uint64_t rejected = 0;
  const auto rejected_at_least = [&](std::uint64_t n) {
    return tachi::test::wait_for_status(status, "tachi-viewer", [&](const tachi_msg_NodeStatus& s) {
      rejected = std::max(rejected, s.rejected);
      return s.rejected >= n;
    }, 10s);
  };

  // A topology whose version jumps by 1000, one indexing particles that do not exist, one with triangles
  // not in threes; states with NaN positions and with the wrong number of them. The topic keeps the last
  // topology per cloth: each bad one is given time to be read before the next replaces it.
  std::vector<std::uint32_t> triangles(t.triangles._buffer, t.triangles._buffer + t.triangles._length);
  tachi_msg_ClothTopology jump = t;
  jump.version = t.version + 1000;
  bad_topology.write(jump);
  ASSERT_TRUE(rejected_at_least(1)) << viewer.err();
  std::vector<std::uint32_t> far = triangles;
  far[4] = 1u << 30;
  tachi_msg_ClothTopology out_of_range = t;
  out_of_range.version = t.version + 1;
  out_of_range.triangles._buffer = far.data();
  bad_topology.write(out_of_range);
  ASSERT_TRUE(rejected_at_least(2)) << viewer.err();
  tachi_msg_ClothTopology ragged = t;
  ragged.version = t.version + 1;
  ragged.triangles._length = t.triangles._length - 1;
  bad_topology.write(ragged);
  std::vector<float> positions(3 * t.particle_grid._length, 0.0f);
  positions[7] = std::numeric_limits<float>::quiet_NaN();
  tachi_msg_ClothState nan{};
  nan.cloth_id = t.cloth_id;
  nan.topology_version = t.version;
  nan.session_id = t.session_id;
  nan.held_particle = -1;
  nan.positions._buffer = positions.data();
  nan.positions._length = nan.positions._maximum = static_cast<std::uint32_t>(positions.size());
  std::vector<float> too_few(30, 0.0f);
  tachi_msg_ClothState short_state = nan;
  short_state.positions._buffer = too_few.data();
  short_state.positions._length = short_state.positions._maximum = static_cast<std::uint32_t>(too_few.size());
  // The state topic keeps the last 2 per cloth and the simulator writes the same cloth at 60 Hz: on a
  // loaded machine its next states can replace a bad one before the viewer reads it. Each bad state
  // goes out three times, so every kind is read at least once (the count below is a lower bound).
  // Each bad state goes out until the viewer counted it (or three times: the count is a lower bound).
  for (const auto* bad : {&nan, &short_state}) {
    const std::uint64_t before = rejected;
    for (int i = 0; i < 3 && rejected == before; ++i) {
      bad_state.write(*bad);
      rejected_at_least(before + 1);
    }
  }
  // The viewer's heartbeat counted every bad input.
  EXPECT_TRUE(rejected_at_least(5)) << "rejected " << rejected << '\n' << viewer.err();
  // A second of video after the bad inputs (20 fps).
  const double frames_now = tachi::test::latest_metric(status, "tachi-viewer", "frames", 10s).value_or(0);
  ASSERT_TRUE(tachi::test::wait_for_metric(status, "tachi-viewer", "frames", frames_now + 21, 20s)) << viewer.err();
  viewer.signal(SIGINT);
  EXPECT_EQ(viewer.wait(2s), 0) << "stops within a second of SIGINT\n" << viewer.err();

  // The last 20 frames of the video (the second after the bad inputs) show the cloth at its centre.
  cv::VideoCapture capture(video);
  ASSERT_TRUE(capture.isOpened()) << video;
  std::vector<bool> cloth_shown;
  const cv::Point centre(pixel_of(0.0f, 0.0f, 320));
  for (cv::Mat frame; capture.read(frame);) {
    const cv::Vec3b p = frame.at<cv::Vec3b>(centre);
    cloth_shown.push_back(p[0] > 100 && p[1] > 100);  // MJPG is lossy: the background is dark, the cloth light
  }
  ASSERT_GT(cloth_shown.size(), 30u);
  EXPECT_EQ(std::count(cloth_shown.end() - 20, cloth_shown.end(), true), 20);
  const cv::Mat last = cv::imread(png);
  ASSERT_FALSE(last.empty());
  EXPECT_NE(last.at<cv::Vec3b>(centre), kBackground);
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0);
}

TEST(ViewerCli, StopsWithinASecondOfSigintEvenAtOneFramePerSecond) {
  ChildProcess viewer({kViewer, "--headless", "--domain", "152", "--fps", "1", "--duration", "60"});
  bus::Participant dds{152};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  // The viewer is in its loop once its heartbeat says RUNNING (or DEGRADED). Its first heartbeat,
  // STARTING, is published as the node is built, before the stop handlers are installed: a SIGINT
  // sent on it killed the viewer by the default action (seen once under a full ctest, 0.28 s).
  ASSERT_TRUE(tachi::test::wait_for_status(status, "tachi-viewer",
                                           [](const tachi_msg_NodeStatus& s) { return s.state != tachi_msg_NODE_STARTING; }, 20s))
      << viewer.err();
  const auto sent = std::chrono::steady_clock::now();
  viewer.signal(SIGINT);
  EXPECT_EQ(viewer.wait(3s), 0) << viewer.err();
  EXPECT_LT(std::chrono::steady_clock::now() - sent, 1s);
}

// The user's path of a viewer that never got to close its video: SIGKILLed (as the launcher's death or
// a power loss ends it) after 4 s of --video. Its MP4 is fragmented, so what it wrote plays: at least
// the fragments before the last second (a keyframe every second; the encoder holds up to ~20 frames).
TEST(ViewerCli, AKilledViewersVideoPlaysUpToItsLastFragment) {
  constexpr unsigned kDomain = 154;
  const tachi::test::ScratchDir dir{"viewer_killed_video"};
  const auto video = (dir / "run.mp4").string();
  ChildProcess viewer({kViewer, "--headless", "--domain", std::to_string(kDomain), "--video", video, "--size", "240", "--fps",
                       "30", "--duration", "60"});
  bus::Participant dds{kDomain};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  ASSERT_TRUE(tachi::test::wait_for_metric(status, "tachi-viewer", "frames", 120, 30s)) << viewer.err();
  viewer.signal(SIGKILL);
  viewer.wait(5s);

  cv::VideoCapture capture(video);
  ASSERT_TRUE(capture.isOpened()) << "a killed viewer's video opens\n" << viewer.err();
  EXPECT_DOUBLE_EQ(capture.get(cv::CAP_PROP_FPS), 30.0);
  int frames = 0;
  for (cv::Mat frame; capture.read(frame); ++frames) ASSERT_EQ(frame.size(), cv::Size(240, 240));
  EXPECT_GE(frames, 60) << "at least 2 s of the 4 s it ran\n" << viewer.err();
}

TEST(ViewerCli, FollowsASimulatorRestart) {
  constexpr unsigned kDomain = 153;
  const tachi::test::ScratchDir dir{"viewer_restart"};
  const auto png = (dir / "last.png").string();
  const std::vector<std::string> sim_args{kSim, "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain),
                                          "--duration", "30"};
  auto first = std::make_unique<ChildProcess>(sim_args);
  ChildProcess viewer({kViewer, "--headless", "--domain", std::to_string(kDomain), "--snapshot", png, "--size", "320",
                       "--duration", "60"});
  bus::Participant dds{kDomain};
  auto strokes = std::make_unique<bus::Writer<tachi_msg_StrokeSample>>(dds, bus::topics::stroke);
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  ASSERT_TRUE(strokes->wait_for_readers(2, 20s)) << first->err() << viewer.err();
  // The first simulator cuts off the lower half (y = -0.1 m), which falls out of view.
  const auto sample = [](std::uint64_t frame, float x, bool cutting) {
    tachi_msg_StrokeSample s{};
    s.sensor_id = 1;
    s.stroke_id = 1;
    s.frame = frame;
    s.time_ns = static_cast<std::int64_t>(frame) * 16'666'667;
    s.position_m = {x, -0.1f, 0.0f};
    s.tracked = true;
    s.gate = cutting ? tachi_msg_GATE_CUTTING : tachi_msg_GATE_IDLE;
    return s;
  };
  for (int i = 0; i <= 40; ++i) {
    strokes->write(sample(static_cast<std::uint64_t>(i), -0.7f + 1.4f * static_cast<float>(i) / 40.0f, true));
    std::this_thread::sleep_for(5ms);
  }
  strokes->write(sample(41, 0.7f, false));
  ASSERT_TRUE(cuts.wait_for_data(10s)) << first->err();
  first->signal(SIGINT);
  EXPECT_EQ(first->wait(10s), 0);
  // The stroke publisher goes too: while it lives, its transient-local history (the newest 256 samples)
  // reaches a simulator that starts late, which cuts the stroke again, as a restarted one should (docs/dds.md).
  strokes.reset();

  // A new simulator: uncut cloth, topology version back to 0. The viewer shows it whole again: it has
  // the new simulator's topology, and has drawn 30 frames since.
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  topologies.take();
  ChildProcess second(sim_args);
  bool uncut = false;
  for (const auto deadline = std::chrono::steady_clock::now() + 20s; !uncut && std::chrono::steady_clock::now() < deadline;) {
    topologies.wait_for_data(1s);
    for (const auto& t : topologies.take()) uncut = uncut || t->version == 0;
  }
  ASSERT_TRUE(uncut) << second.err();
  const double frames_now = tachi::test::latest_metric(status, "tachi-viewer", "frames", 10s).value_or(0);
  ASSERT_TRUE(tachi::test::wait_for_metric(status, "tachi-viewer", "frames", frames_now + 30, 20s)) << viewer.err();
  viewer.signal(SIGINT);
  ASSERT_EQ(viewer.wait(3s), 0) << viewer.err();
  const cv::Mat last = cv::imread(png);
  ASSERT_FALSE(last.empty());
  EXPECT_NE(last.at<cv::Vec3b>(cv::Point(pixel_of(0.0f, -0.3f, 320))), kBackground) << "the lower half is back";
  second.signal(SIGINT);
  EXPECT_EQ(second.wait(10s), 0);
}

// The video's time stamps follow the frames' real times: a viewer that renders fewer frames a second
// than --fps (here 120 at 400 px: ~12 a second on a 2-core machine under a parallel build) still writes a video as long as it ran, instead of
// one that plays fast (the 30 fps video of a viewer rendering ~21 played 1.4x too fast). Domain 216.
TEST(ViewerCli, TheVideoLastsAsLongAsTheViewerRan) {
  const tachi::test::ScratchDir dir{"viewer_video_time"};
  const auto video = (dir / "run.mp4").string();
  const auto started = std::chrono::steady_clock::now();
  const auto r = tachi::test::run({kViewer, "--headless", "--domain", "216", "--video", video, "--size", "400", "--fps", "120",
                                   "--duration", "2"},
                                  60s);
  const double ran_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  cv::VideoCapture capture(video);
  ASSERT_TRUE(capture.isOpened()) << video;
  int frames = 0;
  for (cv::Mat frame; capture.read(frame);) ++frames;
  const double fps = capture.get(cv::CAP_PROP_FPS);
  ASSERT_GT(fps, 0.0);
  // --duration 2: the video covers the 2 s (its last frame is drawn at most a frame's rendering before
  // the viewer stops), and no more than the process ran (writing may make a loaded viewer overrun 2 s).
  EXPECT_GT(frames / fps, 1.75) << frames << " frames at " << fps << " fps\n" << r.err;
  EXPECT_LT(frames / fps, ran_s) << frames << " frames at " << fps << " fps\n" << r.err;
}
