#pragma once
// The DDS Security test PKIs that ctest's TestPki fixture makes once per run (tests/support/CMakeLists.txt):
// "ours" (the CAs every node trusts) and "foreign" (a CA ours does not trust). A test binary run by hand,
// outside ctest, makes a missing one itself (scripts/make_test_pki.sh, ~2 s).
#include "paths.hpp"
#include "process.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>

namespace tachi::test {

inline std::string test_pki(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(binary_dir()) / "test-pki" / name;
  if (!std::filesystem::exists(dir / "permissions.p7s")) {
    using namespace std::chrono_literals;
    const auto r = run({"/bin/bash", source_dir() + "/scripts/make_test_pki.sh", dir.string()}, 60s);
    if (r.exit_code != 0) throw std::runtime_error("make_test_pki.sh " + dir.string() + " failed: " + r.err);
  }
  return dir.string();
}

}  // namespace tachi::test
