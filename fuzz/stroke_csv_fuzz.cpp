// libFuzzer target: the stroke CSV reader (tachi-sim --offline --stroke). Whatever the bytes, every
// sample it keeps is finite, in range and in time order; every row it drops is counted.
#include "tachi/sim/stroke.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  const auto file = tachi::sim::parse_stroke_csv(in);
  if (file.samples.empty() == file.error.empty()) std::abort();  // no samples <=> an error says why
  if (file.problems.size() > file.skipped_rows || file.problems.size() > tachi::sim::StrokeFile::kMaxProblems) std::abort();
  double last_t = -INFINITY;
  for (const auto& s : file.samples) {
    if (!std::isfinite(s.t) || s.t < last_t || std::abs(s.t) > tachi::sim::kMaxStrokeTime_s) std::abort();
    if (!s.position.allFinite() || s.position.cwiseAbs().maxCoeff() > tachi::sim::kMaxStrokeCoordinate_m) std::abort();
    last_t = s.t;
  }
  return 0;
}
