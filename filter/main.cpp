// tachi-filter: raw hand samples -> smoothed, gated strokes. Offline (CSV in, CSV out) or FilterNode on the bus.
#include "cli.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/node.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::filter::Flags flags;
  if (const int rc = tachi::filter::parse_flags(argc, argv, flags); rc >= 0) return rc;
  if (flags.offline) return tachi::filter::run_offline(flags.offline_options, flags.config);
  // Before the node is built: its first heartbeat (STARTING) goes out from its constructor, and a stop
  // that follows it must find the handlers, not the default action that ends the process at once.
  tachi::common::install_stop_handlers();
  const auto& b = flags.bus;
  tachi::bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  tachi::filter::FilterNode node{flags.config, flags.journal, dds};
  return tachi::common::run_until_signal(node);
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-filter: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-filter: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
