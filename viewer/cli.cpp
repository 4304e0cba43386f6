#include "cli.hpp"

#include "tachi/common/disk_full.hpp"

#include <exception>
#include <filesystem>

namespace tachi::viewer {
namespace {
const CLI::Validator kVideoFile(
    [](std::string& path) {
      const auto ext = std::filesystem::path(path).extension().string();
      return ext == ".mp4" || ext == ".avi" ? std::string() : "'" + path + "' must end in .mp4 or .avi";
    },
    "FILE.mp4|FILE.avi");

void add_viewer_flags(CLI::App& app, ViewerOptions& o) {
  common::add_bus_flags(app, o.bus);
  auto* headless = app.add_flag("--headless", o.headless, "No window: render off-screen (use with --video, --snapshot or --frames-dir)");
  app.add_option("--snapshot", o.snapshot, "Write the last rendered frame to this PNG when the viewer stops");
  app.add_option("--snapshot-dir", o.snapshot_dir, "Folder for the snapshots the `p` key saves")->capture_default_str();
  auto* frames = app.add_option("--frames-dir", o.frames_dir, "Write every rendered frame as DIR/frame_NNNNN.png");
  auto* video = app.add_option("--video", o.video, "Write the rendered frames as a video (.mp4: H.264 or MPEG-4; .avi: MJPG)")
                    ->check(kVideoFile);
  auto* mouse = app.add_flag("--mouse", o.mouse,
                             "Seed 001's blade: the cursor cuts the cloth while the left button is held (publishes on "
                             "tachi/hand/stroke as its own hand source)")
                    ->excludes(headless);
  app.add_option("--mouse-sensor-id", o.mouse_sensor_id, "sensor_id of the mouse blade's stroke samples")
      ->needs(mouse)
      ->capture_default_str();
  app.add_option("--mesh", o.mesh, "Offline view of an exported OBJ (tachi-sim --export's cloth.obj; pieces in shades), no DDS")
      ->check(CLI::ExistingFile)
      ->excludes(mouse)
      ->excludes(video)
      ->excludes(frames);
  app.add_option("--fps", o.fps, "Frames rendered per second")
      ->check(CLI::Range(1.0, 240.0))
      ->capture_default_str();
  app.add_option("--size", o.size, "Image width and height in pixels (a window is shrunk to fit the screen)")
      ->check(CLI::Range(64, 4096))
      ->capture_default_str();
  app.add_option("--duration", o.duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM or q)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--exit-when-idle", o.exit_when_idle_s,
                 "Stop when no cloth state arrived for this many seconds after the first one (0: never)")
      ->check(CLI::Range(0.0, 1e7));
}
}  // namespace

int parse_flags(int argc, char** argv, ViewerOptions& options) {
  CLI::App app{"tachi-viewer: shows the cloth, the hand mark (blue idle, green cutting, red outside the cloth), the cut "
               "and a HUD; --mouse turns the cursor into a blade (seed 001); --mesh views an exported mesh offline"};
  app.name("tachi-viewer");
  std::string log_level = "info";
  add_viewer_flags(app, options);
  common::add_log_level_flag(app, log_level);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  common::set_log_level(log_level);
  return -1;
}

void rethrow_naming_a_full_disk(const ViewerOptions& options) {
  for (const std::string& file : {options.video, options.snapshot, options.frames_dir})
    if (!file.empty() && common::out_of_space(file, 0)) throw common::DiskFull(file);
  throw;
}

}  // namespace tachi::viewer
