// tachi-sensor: depth frames in (live Kinect v1 or a fakenect recording), one raw hand sample out
// per depth frame (DDS topic tachi/hand/raw, and/or a CSV): SensorNode, run until the end or a signal.
#include "cli.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/node.hpp"
#include "tachi/sensor/kinect_source.hpp"

#include <exception>
#include <iostream>
#include <optional>

int main(int argc, char** argv) try {
  tachi::sensor::SensorFlags flags;
  if (const int rc = tachi::sensor::parse_sensor_flags(argc, argv, flags); rc >= 0) return rc;
  tachi::common::install_stop_handlers();  // a live Kinect that does not answer is left on a signal
  std::optional<tachi::bus::Participant> dds;
  const auto& b = flags.bus;
  if (!flags.no_dds) dds.emplace(b.domain, b.dds_config, tachi::bus::Security{b.secure_dir, b.identity});
  std::optional<tachi::sensor::SensorNode> node;
  try {
    node.emplace(flags.options, dds ? &*dds : nullptr);
  } catch (const tachi::sensor::NoKinectError& e) {
    std::cerr << "tachi-sensor: " << e.what() << '\n';
    return tachi::common::kExitNoDevice;
  }
  return tachi::common::run_until_signal(*node);
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-sensor: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-sensor: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
