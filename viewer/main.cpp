// tachi-viewer: draws the cloth, the hand mark, the cut and a HUD from the DDS bus, in a window or
// headless (PNG frames, video); --mesh shows an exported mesh without DDS; --mouse cuts with the mouse.
#include "live.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/common/app.hpp"

#include <iostream>

int main(int argc, char** argv) try {
  CLI::App app{"tachi-viewer: shows the cloth, the hand mark (blue idle, green cutting, red outside the cloth), the cut "
               "and a HUD; --mouse turns the cursor into a blade (seed 001); --mesh views an exported mesh offline"};
  app.name("tachi-viewer");
  tachi::viewer::ViewerOptions options;
  std::string log_level = "info";
  tachi::viewer::add_viewer_flags(app, options);
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(log_level);
  tachi::common::install_stop_handlers();
  try {
    return options.mesh.empty() ? tachi::viewer::run_live(options) : tachi::viewer::run_mesh(options);
  } catch (const tachi::common::DiskFull&) {
    throw;
  } catch (const std::exception&) {
    // OpenCV's writers say a full disk only as an assertion or a false return: the filesystem of the
    // viewer's own outputs tells whether that is what happened.
    for (const std::string& file : {options.video, options.snapshot, options.frames_dir})
      if (!file.empty() && tachi::common::out_of_space(file, 0)) throw tachi::common::DiskFull(file);
    throw;
  }
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-viewer: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-viewer: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
