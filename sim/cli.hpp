// tachi-sim's flags: registered here, by the executable, so the libraries do not need CLI11 for them.
#pragma once

#include "tachi/common/app.hpp"
#include "tachi/sim/node.hpp"
#include "tachi/sim/object.hpp"
#include "tachi/sim/offline.hpp"

namespace tachi::sim {

struct Flags {
  bool offline = false;
  OfflineOptions options;  ///< shared by the offline driver and the live node
  LiveOptions live;
  ObjectOptions object;
  common::BusOptions bus;
};

/// Parses argv (and applies --log-level). An exit code when the process should stop now, else -1.
int parse_flags(int argc, char** argv, Flags& flags);
/// --offline: simulates, prints (or exports) the summary. The exit code.
int run_offline_and_report(const OfflineOptions& options);

}  // namespace tachi::sim
