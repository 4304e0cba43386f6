// A flat square "table" of points as an ascii PLY, the object the hands-on tests drape the cloth over:
// (2 half + 1)^2 points `spacing_m` apart in the x-y plane, centred at the origin (place it with
// tachi-sim --object-pose).
#pragma once

#include <filesystem>
#include <fstream>

namespace tachi::test {

inline void write_table_ply(const std::filesystem::path& path, int half, double spacing_m) {
  const int side = 2 * half + 1;
  std::ofstream out{path};
  out << "ply\nformat ascii 1.0\nelement vertex " << side * side
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (int i = -half; i <= half; ++i)
    for (int k = -half; k <= half; ++k) out << spacing_m * i << ' ' << spacing_m * k << " 0\n";
}

}  // namespace tachi::test
