// tachi-sim: the cloth simulator process. --offline runs the library's offline driver (no DDS); the
// live mode is SimNode on the DDS pipeline (strokes in; topology, state and cuts out).
#include "cli.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/node.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::sim::Flags flags;
  if (const int rc = tachi::sim::parse_flags(argc, argv, flags); rc >= 0) return rc;
  if (flags.offline) return tachi::sim::run_offline_and_report(flags.options);
  tachi::common::install_stop_handlers();  // before the journal replay, which a stop must not kill midway
  const auto& b = flags.bus;
  tachi::bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  tachi::sim::SimNode node{flags.options, flags.live, dds};
  return tachi::common::run_until_signal(node);
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-sim: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-sim: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
