// tachi-filter's flags: registered here, by the executable; the libraries do not need CLI11 for them.
#pragma once

#include "tachi/common/app.hpp"
#include "tachi/filter/config.hpp"
#include "tachi/filter/node.hpp"

namespace tachi::filter {

struct Flags {
  bool offline = false;
  OfflineFilterOptions offline_options;
  FilterConfig config;  ///< --config with --smoother and --gate applied
  std::string journal;
  common::BusOptions bus;
};

/// Parses argv, applies --log-level and loads the config. An exit code when the process should stop now
/// (help, --print-config, a bad flag or config: kExitUsage naming it), else -1.
int parse_flags(int argc, char** argv, Flags& flags);

}  // namespace tachi::filter
