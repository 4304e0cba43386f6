// tachi-viewer's real window under Xvfb: it fits a small screen and shows the cloth (checked on a
// screenshot taken with imagemagick's `import`), its keys work, and a real mouse drag driven by
// xdotool with --mouse makes the real tachi-sim cut the cloth along the dragged line (seed 001 sec. 3).
// Domain ids 155-159 (docs/testing.md).
#include "viewer_process.hpp"
#include "node_status.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <thread>

// Last: Xlib's macros (None, Bool, Status) would break the headers above.
#include <X11/Xlib.h>
#include <X11/extensions/Xfixes.h>

using namespace std::chrono_literals;
namespace bus = tachi::bus;
using tachi::test::ChildProcess;

namespace {
// Found by CMake (empty when missing: the tests skip, scripts/setup.sh installs them).
const std::string kXvfb = TACHI_XVFB_EXE;
const std::string kXdotool = TACHI_XDOTOOL_EXE;
const std::string kImport = TACHI_IMPORT_EXE;

// An X server of its own for each test, on a display number no other one holds.
class VirtualDisplay {
 public:
  VirtualDisplay(int width, int height) {
    // At most kTries servers started: an Xvfb that cannot start at all must fail the test (running() says
    // so), not try every number.
    constexpr int kTries = 10;
    for (int n = 150 + ::getpid() % 400, tries = 0; tries < kTries; ++n) {
      const std::string number = std::to_string(n);
      const auto lock = std::filesystem::path("/tmp") / (".X" + number + "-lock");
      if (held(lock)) continue;
      ++tries;
      name_ = ":" + number;
      char screen[32];
      std::snprintf(screen, sizeof screen, "%dx%dx24", width, height);
      // -noreset: an X server resets when its last client leaves, and refuses connections while it does. Our
      // probe below is a client: the viewer started right after it found no display (CI, 2026-12-07: "could
      // not connect to display", the server up; in full ctest runs only).
      server_ = std::make_unique<ChildProcess>(
          std::vector<std::string>{kXvfb, name_, "-screen", "0", screen, "-nolisten", "tcp", "-noreset"});
      // Ours once the lock names our server and a client connects. The socket's existence said less: a
      // socket left by a killed server, or another test's server that took the number between the lock
      // check and Xvfb's start (ours then exits, "server already active"), let the viewer start before
      // or beside our server (seen in full ctest runs: no window, or one never fitted to the screen).
      for (int i = 0; i < 200 && server_->running(); ++i) {
        std::ifstream in(lock);
        pid_t owner = 0;
        if (in >> owner && owner == server_->pid()) {
          if (Display* display = XOpenDisplay(name_.c_str())) {
            XCloseDisplay(display);
            ready_ = true;
            return;
          }
        }
        std::this_thread::sleep_for(50ms);
      }
      if (server_->running()) {  // up but not ready in 10 s: not ours to use
        server_->signal(SIGTERM);
        server_->wait(3s);
      }
      server_->wait(1s);  // exited: its stderr says why
      failure_ = "Xvfb " + name_ + " did not start: " + server_->err();
    }
  }
  /// Whether an X server of this test's own answered (else why not: the last Xvfb's stderr). A test
  /// asserts it first: a viewer started on a display no server of ours holds can only time out.
  bool ready() const { return ready_; }
  const std::string& failure() const { return failure_; }
  /// Whether a display's lock names a live server (Xvfb replaces a lock whose server is gone).
  static bool held(const std::filesystem::path& lock) {
    std::ifstream in(lock);
    pid_t owner = 0;
    if (!(in >> owner)) return std::filesystem::exists(lock);  // being written: taken
    return ::kill(owner, 0) == 0 || errno == EPERM;
  }
  /// Whether this test's X server is still up (a window search that finds nothing says which side failed).
  bool running() const { return server_ && server_->running(); }
  ~VirtualDisplay() {
    // Waited for: killed at once (ChildProcess's destructor), Xvfb left its lock and socket behind, and
    // /tmp filled up with them (123 of the 400 numbers this test draws from, 2026-12-05).
    if (server_) {
      server_->signal(SIGTERM);
      server_->wait(3s);
    }
  }
  const std::string& name() const { return name_; }
  std::map<std::string, std::string> env() const { return {{"DISPLAY", name_}}; }
  /// Runs an X client (xdotool, import) on this display; returns its stdout.
  std::string run(std::vector<std::string> argv) const {
    const auto r = tachi::test::run(std::move(argv), 20s, env());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  }
  cv::Mat screenshot(const std::filesystem::path& file) const {
    run({kImport, "-window", "root", file.string()});
    return cv::imread(file.string());
  }
  /// The id of the viewer's window, waiting until it is mapped (up to 40 s: a loaded ctest -j3 on two
  /// cores runs a dozen processes at once), or none once the viewer has exited.
  std::string viewer_window(ChildProcess& viewer) const {
    for (const auto deadline = std::chrono::steady_clock::now() + 40s; std::chrono::steady_clock::now() < deadline;) {
      const auto r = tachi::test::run({kXdotool, "search", "--onlyvisible", "--name", "^tachi$"}, 10s, env());
      if (r.exit_code == 0 && !r.out.empty()) return r.out.substr(0, r.out.find('\n'));
      if (!viewer.running()) return {};
      std::this_thread::sleep_for(100ms);
    }
    return {};
  }
  /// Every named window on this display and its name, for a failure message (the window search failed
  /// twice in CI, 2026-12-04 and 12-05, and never by hand: what the display held is the clue).
  std::string window_names() const {
    const auto r = tachi::test::run({kXdotool, "search", "--name", ".", "getwindowname", "%@"}, 10s, env());
    return "windows on " + name_ + ": [" + r.out + "] (xdotool exit " + std::to_string(r.exit_code) + ")";
  }
  /// Whether the pointer, where it is, shows any pixel (its image as XFixes reports it).
  bool pointer_visible() const {
    Display* display = XOpenDisplay(name_.c_str());
    if (display == nullptr) return false;
    bool visible = false;
    if (XFixesCursorImage* image = XFixesGetCursorImage(display)) {
      for (int i = 0; i < image->width * image->height && !visible; ++i) visible = (image->pixels[i] >> 24) != 0;
      XFree(image);
    }
    XCloseDisplay(display);
    return visible;
  }
  cv::Rect geometry(const std::string& window) const {
    const std::string out = run({kXdotool, "getwindowgeometry", window});
    std::smatch m;
    if (!std::regex_search(out, m, std::regex(R"(Position: (-?\d+),(-?\d+).*\n.*Geometry: (\d+)x(\d+))"))) return {};
    return {std::stoi(m[1]), std::stoi(m[2]), std::stoi(m[3]), std::stoi(m[4])};
  }

 private:
  std::string name_;
  std::unique_ptr<ChildProcess> server_;
  bool ready_ = false;
  std::string failure_;
};

bool tools_present() {
  for (const auto& tool : {kXvfb, kXdotool, kImport})
    if (tool.empty() || !std::filesystem::exists(tool)) return false;
  return true;
}

// Light cloth pixels (front shade) vs the dark background.
bool is_cloth(const cv::Vec3b& p) { return p[0] > 120 && p[1] > 110 && p[2] > 90; }

// Polls `done` until it holds or `timeout` passes (what a window shows changes when Qt and X get to it,
// with no event a test can wait on).
bool eventually(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  for (const auto deadline = std::chrono::steady_clock::now() + timeout; std::chrono::steady_clock::now() < deadline;) {
    if (done()) return true;
    std::this_thread::sleep_for(50ms);
  }
  return done();
}

// Waits until the viewer has drawn `frames` more frames than it had (its heartbeat's "frames" figure).
bool frames_drawn(bus::Reader<tachi_msg_NodeStatus>& status, double frames) {
  const double now = tachi::test::latest_metric(status, "tachi-viewer", "frames", 10s).value_or(0);
  return tachi::test::wait_for_metric(status, "tachi-viewer", "frames", now + frames, 20s).has_value();
}

// Waits until the viewer has the cloth (its heartbeat no longer says it waits for one) and drew it.
bool viewer_has_cloth(bus::Reader<tachi_msg_NodeStatus>& status) {
  return tachi::test::wait_for_status(status, "tachi-viewer", [](const tachi_msg_NodeStatus& s) {
    return std::string(s.detail).empty() && tachi::test::metric(s, "frames").value_or(0) > 0;
  }, 20s) && frames_drawn(status, 2);
}

// The viewer's last heartbeat in words (its state detail and frames drawn), for a failure message.
std::string last_detail(bus::Reader<tachi_msg_NodeStatus>& status) {
  std::string said = "none in 2 s";
  tachi::test::wait_for_status(status, "tachi-viewer", [&](const tachi_msg_NodeStatus& s) {
    said = std::string(s.detail);
    said.append(" (frames ").append(std::to_string(tachi::test::metric(s, "frames").value_or(-1))).append(")");
    return false;
  }, 2s);
  return said;
}

// Why no viewer window was found: which side is gone, what the display holds, the viewer's last
// heartbeat and its stderr (read after running(), which drains it: err() alone says only what an
// earlier wait read, and said nothing when the mouse-drag test failed in CI, 2026-12-06).
std::string no_window(const VirtualDisplay& display, ChildProcess& viewer, bus::Reader<tachi_msg_NodeStatus>& status) {
  const bool viewer_running = viewer.running();
  return "X server " + std::string(display.running() ? "up" : "gone") + " on " + display.name() + ", viewer " +
         (viewer_running ? "running" : "exited") + "; " + display.window_names() +
         "; viewer's heartbeat: " + last_detail(status) + "; stderr: " + viewer.err();
}

}  // namespace

TEST(ViewerWindow, FitsASmallScreenShowsTheClothAndSavesASnapshotOnAKey) {
  if (!tools_present()) GTEST_SKIP() << "Xvfb, xdotool or imagemagick missing (scripts/setup.sh installs them)";
  const tachi::test::ScratchDir dir{"viewer_window"};
  const VirtualDisplay display(1024, 700);
  ASSERT_TRUE(display.ready()) << display.failure();
  const std::string domain = "155";
  ChildProcess sim({kSim, "--grid", "16", "--pin", "top-edge", "--domain", domain, "--duration", "30"});
  ChildProcess viewer({kViewer, "--domain", domain, "--size", "1000", "--snapshot-dir", dir.path().string()}, display.env());
  bus::Participant dds{155};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  const std::string window = display.viewer_window(viewer);
  ASSERT_FALSE(window.empty()) << no_window(display, viewer, status);
  ASSERT_TRUE(viewer_has_cloth(status)) << last_detail(status) << "; stderr: " << viewer.err();

  // Qt applies the fitted size asynchronously (seen once in a loaded ctest -j2 run: still 1000 px after
  // 2 s): the settled geometry is what a user sees, so it is read again for up to 3 s more.
  cv::Rect where;
  eventually([&] { return (where = display.geometry(window)).height <= 700; }, 3s);
  EXPECT_LE(where.height, 700) << "a 1000 px window is shrunk to the 700 px screen; stderr: " << viewer.err();
  EXPECT_GT(where.height, 400);
  EXPECT_LE(where.br().y, 700);
  EXPECT_LE(where.br().x, 1024);
  const cv::Mat shot = display.screenshot(dir / "screen.png");
  ASSERT_FALSE(shot.empty());
  const int side = std::min(where.width, where.height);
  const cv::Point centre = cv::Point(where.tl()) + cv::Point(pixel_of(0.0f, 0.0f, side));
  EXPECT_TRUE(is_cloth(shot.at<cv::Vec3b>(centre))) << "cloth at the window's centre " << centre;
  const cv::Point beside = cv::Point(where.tl()) + cv::Point(pixel_of(0.75f, 0.0f, side));
  EXPECT_FALSE(is_cloth(shot.at<cv::Vec3b>(beside))) << "background beside the cloth";

  // Resized, the window draws at its new size: the cloth is again at the centre of the smaller side.
  display.run({kXdotool, "windowsize", "--sync", window, "500", "400"});
  ASSERT_TRUE(frames_drawn(status, 5)) << viewer.err();
  const cv::Rect resized = display.geometry(window);
  const cv::Mat small_shot = display.screenshot(dir / "resized.png");
  ASSERT_FALSE(small_shot.empty());
  const int small_side = std::min(resized.width, resized.height);
  EXPECT_LT(small_side, side);
  const cv::Point2f offset((static_cast<float>(resized.width - small_side)) / 2, (static_cast<float>(resized.height - small_side)) / 2);
  EXPECT_TRUE(is_cloth(small_shot.at<cv::Vec3b>(cv::Point(resized.tl()) + cv::Point(offset + pixel_of(0.0f, 0.2f, small_side)))));
  EXPECT_FALSE(is_cloth(small_shot.at<cv::Vec3b>(cv::Point(resized.tl()) + cv::Point(offset + pixel_of(0.0f, 0.65f, small_side)))));
  // Beside the cloth's right edge: a stretched copy of the old square image would still show cloth here.
  EXPECT_FALSE(is_cloth(small_shot.at<cv::Vec3b>(cv::Point(resized.tl()) + cv::Point(offset + pixel_of(0.56f, 0.2f, small_side)))));

  // `h` lists the keys over the picture (white text below the HUD, where there was none).
  const auto white_text = [&](const cv::Mat& image) {
    const cv::Rect below_hud = cv::Rect(resized.x + 60, resized.y + 100, 380, 150) & cv::Rect(0, 0, image.cols, image.rows);
    cv::Mat white;
    cv::inRange(image(below_hud), cv::Scalar(225, 225, 225), cv::Scalar(255, 255, 255), white);
    return cv::countNonZero(white);
  };
  EXPECT_LT(white_text(small_shot), 20);
  display.run({kXdotool, "windowfocus", "--sync", window, "key", "h"});
  EXPECT_TRUE(eventually([&] { return white_text(display.screenshot(dir / "help.png")) > 60; }, 5s)) << "the key list is shown";

  display.run({kXdotool, "mousemove", "--window", window, "100", "100"});
  EXPECT_TRUE(display.pointer_visible()) << "without --mouse the system pointer stays";

  display.run({kXdotool, "windowfocus", "--sync", window, "key", "p"});
  EXPECT_TRUE(eventually([&] { return std::filesystem::exists(dir / "tachi_snapshot_1.png"); }, 5s)) << viewer.err();
  display.run({kXdotool, "windowfocus", "--sync", window, "key", "q"});
  EXPECT_EQ(viewer.wait(5s), 0) << viewer.err();
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(5s), 0);
}

TEST(ViewerWindow, AMouseDragCutsTheClothAlongTheDraggedLine) {
  if (!tools_present()) GTEST_SKIP() << "Xvfb, xdotool or imagemagick missing (scripts/setup.sh installs them)";
  const VirtualDisplay display(1024, 900);
  ASSERT_TRUE(display.ready()) << display.failure();
  constexpr unsigned kDomain = 156;
  ChildProcess sim({kSim, "--grid", "16", "--pin", "top-edge", "--domain", std::to_string(kDomain), "--duration", "40"});
  ChildProcess viewer({kViewer, "--domain", std::to_string(kDomain), "--size", "600", "--mouse"}, display.env());
  bus::Participant dds{kDomain};
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  bus::Reader<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_ClothState> states{dds, bus::topics::cloth_state};
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  bus::Reader<tachi_msg_NodeStatus> status{dds, bus::topics::node_status};
  const std::string window = display.viewer_window(viewer);
  ASSERT_FALSE(window.empty()) << no_window(display, viewer, status);
  ASSERT_TRUE(states.wait_for_data(20s)) << sim.err();
  ASSERT_TRUE(viewer_has_cloth(status)) << viewer.err();  // the cloth to cast the cursor onto

  // Seed 001: the blade image drawn at the cursor replaces the system pointer.
  display.run({kXdotool, "mousemove", "--window", window, "100", "100"});
  EXPECT_TRUE(eventually([&] { return !display.pointer_visible(); }, 5s));

  // Drag from left of the cloth to right of it at y = -0.1 m: grid row (0.5 + 0.1) * 15 = 9.
  const cv::Rect where = display.geometry(window);
  const int side = std::min(where.width, where.height);
  const cv::Point from(pixel_of(-0.75f, -0.1f, side)), to(pixel_of(0.75f, -0.1f, side));
  // One xdotool process for the whole drag (its commands chained): thirty processes, one a move, took
  // seconds on a loaded machine, and the blade then met a cloth already falling from the cut's start.
  std::vector<std::string> drag{kXdotool, "mousemove", "--window", window, std::to_string(from.x), std::to_string(from.y), "mousedown", "1"};
  for (int i = 1; i <= 30; ++i) {
    const int x = from.x + (to.x - from.x) * i / 30;
    drag.insert(drag.end(), {"mousemove", "--window", window, std::to_string(x), std::to_string(from.y), "sleep", "0.01"});
  }
  drag.insert(drag.end(), {"mouseup", "1"});
  display.run(drag);

  bool cut = false;
  std::uint32_t pieces = 0, sensor = 0;
  std::vector<std::pair<int, int>> line;  // grid cells of the cut (grid mode; exact cuts report none)
  for (int i = 0; i < 100 && !cut; ++i) {
    cuts.wait_for_data(100ms);
    for (const auto& event : cuts.take()) {
      cut = true;
      pieces = event->pieces;
      sensor = event->sensor_id;
      for (std::uint32_t k = 0; k < event->cut_line._length; ++k)
        line.emplace_back(event->cut_line._buffer[k].u, event->cut_line._buffer[k].v);
    }
  }
  ASSERT_TRUE(cut) << "the simulator reported no cut\n" << sim.err() << viewer.err();
  EXPECT_EQ(pieces, 2u);
  EXPECT_EQ(sensor, 1000u) << "the cut names the mouse blade as its hand source";
  for (const auto& [u, v] : line) EXPECT_NEAR(v, 9, 1) << "cell (" << u << ", " << v << ") is off the dragged line";

  // Whatever the cut mode: the cloth parted along row 9 within a cell. Soon every particle of rows 0-7
  // still hangs where it was and every particle of rows 11-15 has fallen away.
  int hanging = 0, fallen = 0, misplaced = 0;
  std::vector<bus::Owned<tachi_msg_ClothTopology>> shapes;
  const auto parted = [&] {
    for (auto& t : topologies.take()) shapes.push_back(std::move(t));
    const auto latest = states.take();
    if (latest.empty() || shapes.empty()) return false;
    const tachi_msg_ClothState& now = *latest.back();
    const tachi_msg_ClothTopology& shape = *shapes.back();
    hanging = fallen = misplaced = 0;
    for (std::uint32_t i = 0; i < shape.particle_grid._length && 3 * i + 1 < now.positions._length; ++i) {
      const int v = shape.particle_grid._buffer[i].v;
      const float rest_y = 0.5f - static_cast<float>(v) / 15.0f;
      const float y = now.positions._buffer[3 * i + 1];
      if (v <= 7) (std::abs(y - rest_y) < 0.2f ? hanging : misplaced)++;
      if (v >= 11) (y < rest_y - 0.5f ? fallen : misplaced)++;
    }
    return misplaced == 0 && hanging >= 8 * 16 && fallen >= 5 * 16;
  };
  eventually(parted, 10s);
  EXPECT_EQ(misplaced, 0);
  EXPECT_GE(hanging, 8 * 16);
  EXPECT_GE(fallen, 5 * 16);

  // The samples that made the cut came from the mouse as a hand source of its own.
  bool from_mouse = false;
  for (const auto& s : strokes.take(1024))
    if (s->opened_by == tachi_msg_GATE_SOURCE_MOUSE && s->sensor_id == 1000 && s->gate == tachi_msg_GATE_CUTTING &&
        s->session_id != 0 && s->acquired_ns > 0)
      from_mouse = true;
  EXPECT_TRUE(from_mouse);
  viewer.signal(SIGINT);
  EXPECT_EQ(viewer.wait(3s), 0) << viewer.err();
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(5s), 0);
}
