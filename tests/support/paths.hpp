// Where the build put the executables, the recordings and the sources, found at run time, not
// compiled in: a path in a -D definition differs between two checkouts, so ccache could never reuse
// a test's object file in a fresh clone (CI). The test binaries live in the build's bin/ folder with
// every executable; CMake writes bin/tachi_test_paths.txt beside them (tests/support/CMakeLists.txt).
#pragma once

#include <string>

namespace tachi::test {

/// The folder of the running test binary: every executable of the build (tachi, tachi-sim, ...).
[[nodiscard]] const std::string& bin_dir();
/// bin_dir() + "/" + name.
[[nodiscard]] std::string executable(const std::string& name);
/// The rendered recordings (build/recordings, or the tree TACHI_RECORDINGS_FROM named).
[[nodiscard]] const std::string& recordings_dir();
/// The checkout (config/, scripts/, recordings/scenarios/).
[[nodiscard]] const std::string& source_dir();
/// The build tree.
[[nodiscard]] const std::string& binary_dir();

}  // namespace tachi::test
