// Every node's exit codes, in one place: the nodes return them and `tachi run` (launcher/src/
// supervision.cpp) decides from them whether a restart can help (docs/cli.md "Exit codes").
#pragma once

namespace tachi::common {

/// Process exit codes shared by every executable.
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,   ///< runtime error: bad input data, lost peer, I/O failure (a restart may help)
  kExitUsage = 2,     ///< bad flags: one line names the flag and the allowed range
  kExitNoDevice = 3,  ///< no Kinect found (live mode only)
  // 4 is `tachi run`'s own "a child kept dying" (launcher/include/tachi/launcher/supervision.hpp).
  kExitDiskFull = 5,  ///< an output could not be written: no space left on device (a restart cannot help)
};

}  // namespace tachi::common
