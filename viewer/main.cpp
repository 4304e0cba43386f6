// tachi-viewer: draws the cloth, the hand mark, the cut and a HUD from the DDS bus, in a window or
// headless (PNG frames, video); --mesh shows an exported mesh without DDS; --mouse cuts with the mouse.
#include "cli.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/common/node.hpp"
#include "window.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::viewer::ViewerOptions options;
  if (const int rc = tachi::viewer::parse_flags(argc, argv, options); rc >= 0) return rc;
  try {
    const auto window = tachi::viewer::open_window(options);  // none with --headless
    if (!options.mesh.empty()) {
      tachi::viewer::MeshView view{options, window.get()};
      return tachi::common::run_until_signal(view);
    }
    // Before the node is built: its first heartbeat (STARTING) goes out from its constructor, and a
    // stop that follows it must find the handlers, not the default action that ends the process at once.
    tachi::common::install_stop_handlers();
    const auto& b = options.bus;
    tachi::bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, tachi::viewer::participant_identity(options)}};
    tachi::viewer::ViewerNode node{options, dds, window.get()};
    return tachi::common::run_until_signal(node);
  } catch (const tachi::common::DiskFull&) {
    throw;
  } catch (const std::exception&) {
    tachi::viewer::rethrow_naming_a_full_disk(options);
  }
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-viewer: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-viewer: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
