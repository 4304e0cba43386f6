// tachi-viewer's options (flags in viewer/cli.cpp): live on the DDS bus (window or headless, optionally the
// mouse blade), or the offline view of an exported mesh.
#pragma once

#include "tachi/common/app.hpp"

#include <cstdint>
#include <string>

namespace tachi::viewer {

struct ViewerOptions {
  common::BusOptions bus;
  bool headless = false;
  std::string snapshot;            ///< PNG of the last frame, written when the viewer stops
  std::string snapshot_dir = ".";  ///< where the `p` key saves snapshots
  std::string frames_dir;          ///< every frame as PNG
  std::string video;               ///< .mp4 or .avi
  std::string mesh;                ///< offline view of this OBJ
  bool mouse = false;              ///< seed 001's mouse blade
  std::uint32_t mouse_sensor_id = 1000;
  double fps = 30.0;
  double duration_s = 0.0;
  double exit_when_idle_s = 0.0;
  int size = 800;
};

}  // namespace tachi::viewer
