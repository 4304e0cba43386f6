// tachi-viewer's flags: registered here, by the executable; the libraries do not need CLI11 for them.
#pragma once

#include "tachi/viewer/options.hpp"

namespace tachi::viewer {

/// Parses argv (every flag validated when parsed, each error naming its flag; non-finite numbers such as
/// `--fps nan` refused) and applies --log-level. An exit code when the process should stop now, else -1.
int parse_flags(int argc, char** argv, ViewerOptions& options);

/// For a catch block around the viewer's run: OpenCV's writers say a full disk only as an assertion or a
/// false return, so the filesystem of the viewer's own outputs tells whether that is what happened.
/// Throws DiskFull naming the output when one has no room left, else rethrows the current exception.
[[noreturn]] void rethrow_naming_a_full_disk(const ViewerOptions& options);

}  // namespace tachi::viewer
