// tachi-viewer's flags: registered here, by the executable; the libraries do not need CLI11 for them.
#pragma once

#include "tachi/viewer/options.hpp"

namespace tachi::viewer {

/// Parses argv (every flag validated when parsed, each error naming its flag; non-finite numbers such as
/// `--fps nan` refused) and applies --log-level. An exit code when the process should stop now, else -1.
int parse_flags(int argc, char** argv, ViewerOptions& options);

}  // namespace tachi::viewer
