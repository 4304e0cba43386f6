// tachi-viewer: draws the cloth, the hand mark and the cut from the DDS bus, in a window or headless.
#include "src/bus_adapter.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/common/app.hpp"

#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>

using namespace std::chrono_literals;
namespace viewer = tachi::viewer;

namespace {
struct Options {
  tachi::common::BusOptions bus;
  std::string log_level;
  bool headless = false;
  std::string snapshot;
  std::string frames_dir;
  double fps = 30.0;
  double duration_s = 0.0;
  double exit_when_idle_s = 0.0;
  int size = 800;
};

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write image " + path);
}
}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-viewer: shows the cloth, the hand mark (blue idle, green cutting, red outside the cloth) and the cut"};
  app.name("tachi-viewer");
  Options o;
  tachi::common::add_bus_flags(app, o.bus);
  tachi::common::add_log_level_flag(app, o.log_level);
  app.add_flag("--headless", o.headless, "No window: render off-screen (use with --snapshot or --frames-dir)");
  app.add_option("--snapshot", o.snapshot, "Write the last rendered frame to this PNG when the viewer stops");
  app.add_option("--frames-dir", o.frames_dir, "Write every rendered frame as DIR/frame_NNNNN.png");
  app.add_option("--fps", o.fps, "Frames rendered per second")->check(CLI::Range(1.0, 240.0))->capture_default_str();
  app.add_option("--size", o.size, "Image width and height in pixels")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--duration", o.duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--exit-when-idle", o.exit_when_idle_s,
                 "Stop when no cloth state arrived for this many seconds after the first one (0: never)")
      ->check(CLI::NonNegativeNumber);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(o.log_level);
  tachi::common::install_stop_handlers();
  if (!o.headless && std::getenv("DISPLAY") == nullptr)
    throw std::runtime_error("no display (DISPLAY is not set); use --headless with --snapshot or --frames-dir");
  if (!o.frames_dir.empty()) std::filesystem::create_directories(o.frames_dir);

  tachi::bus::Participant dds{o.bus.domain, o.bus.dds_config, {o.bus.secure_dir, o.bus.identity}};
  tachi::bus::Reader<tachi_msg_ClothTopology> topologies{dds, tachi::bus::topics::cloth_topology};
  tachi::bus::Reader<tachi_msg_ClothState> states{dds, tachi::bus::topics::cloth_state};
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes{dds, tachi::bus::topics::stroke};
  tachi::bus::WaitSet waitset{dds};
  waitset.attach(topologies);
  waitset.attach(states);
  waitset.attach(strokes);

  tachi::bus::Heartbeat heartbeat{dds, "tachi-viewer"};
  tachi::bus::InputGuard guard{[&](std::string_view reason) {
    heartbeat.count_rejected(reason);
    spdlog::warn("tachi-viewer: cloth message rejected ({})", reason);
  }};
  std::uint64_t messages_in = 0;
  viewer::SceneState scene;
  viewer::View view;
  view.width = view.height = o.size;
  const auto frame_period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(1.0 / o.fps));
  const auto start = std::chrono::steady_clock::now();
  auto next_frame = start;
  auto last_state = start;
  std::uint64_t frames = 0;
  cv::Mat image;
  const std::string window = "tachi";

  tachi::common::run_until_stopped([&] {
    const auto now = std::chrono::steady_clock::now();
    // At most 100 ms: a signal does not wake a DDS waitset, and at --fps 1 a whole frame is too long to stop in.
    waitset.wait(std::clamp(next_frame - now, std::chrono::steady_clock::duration(1ms), std::chrono::steady_clock::duration(100ms)));
    for (const auto& t : topologies.take()) {
      ++messages_in;
      if (viewer::plausible(*t, guard)) scene.on_topology(viewer::from_msg(*t));
    }
    for (const auto& s : states.take(8)) {
      if (!viewer::plausible(*s, guard)) continue;
      scene.on_state(viewer::from_msg(*s));
      last_state = std::chrono::steady_clock::now();
      ++messages_in;
    }
    for (const auto& h : strokes.take()) {
      scene.on_hand(viewer::from_msg(*h));
      ++messages_in;
    }
    heartbeat.update(tachi_msg_NODE_RUNNING, messages_in, frames, scene.has_cloth() ? "" : "waiting for the cloth");

    if (std::chrono::steady_clock::now() >= next_frame) {
      next_frame += frame_period;
      image = viewer::render(scene.scene(), view);
      if (!o.frames_dir.empty()) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05llu.png", static_cast<unsigned long long>(frames));
        write_image((std::filesystem::path(o.frames_dir) / name).string(), image);
      }
      ++frames;
      if (!o.headless) {
        cv::imshow(window, image);
        const int key = cv::waitKey(1);
        if (key == 'q' || key == 27) return false;
      }
    }
    const auto elapsed = std::chrono::steady_clock::now() - start;
    if (o.duration_s > 0 && elapsed > std::chrono::duration<double>(o.duration_s)) return false;
    if (o.exit_when_idle_s > 0 && scene.states_received() > 0 &&
        std::chrono::steady_clock::now() - last_state > std::chrono::duration<double>(o.exit_when_idle_s))
      return false;
    return true;
  });

  if (image.empty()) image = viewer::render(scene.scene(), view);
  if (!o.snapshot.empty()) write_image(o.snapshot, image);
  spdlog::info("tachi-viewer: {} frames rendered, {} cloth states received", frames, scene.states_received());
  return 0;
} catch (const std::exception& e) {
  std::cerr << "tachi-viewer: " << e.what() << '\n';
  return 1;
}
