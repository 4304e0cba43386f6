// tachi-sensor-eval's work, as a library: scores a tachi-sensor hand CSV against its ground truth, or renders
// and scores a range of randomized clips in memory (clip_score.hpp), and prints the result as text or JSON.
// The executable only parses flags (sensor/eval_cli.cpp).
#pragma once

#include "tachi/sensor/clip_score.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "tachi/sensor/random_scene.hpp"

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace tachi::sensor {

/// Seeds FIRST..LAST, inclusive.
struct SeedRange {
  std::uint64_t first = 0;
  std::uint64_t last = 0;
};
/// "FIRST..LAST" with FIRST <= LAST, or one seed; nothing for anything else.
std::optional<SeedRange> parse_seed_range(const std::string& text);

/// The randomized clips of a seed range, each scored by a fresh hand finder.
struct RandomRun {
  SeedRange seeds;
  std::vector<ScenarioSpec> specs;
  std::vector<ClipScore> clips;
  Summary summary;
};
/// Renders and scores every clip of `seeds`, `jobs` at a time (each with one OpenCV thread).
RandomRun score_random(SeedRange seeds, unsigned jobs, bool hanging_rest = true);

/// "up", "raised", "never": when the clip's hand comes up.
const char* start_name(HandStart start);

/// Limits on a CSV evaluation (negative: not checked).
struct EvaluationLimits {
  double max_rms_m = -1;
  double min_tracked_ratio = -1;
  long max_phantoms = -1;
  [[nodiscard]] bool met(const Evaluation& e) const;
};

struct EvaluationOptions {
  std::string hands_csv;   ///< tachi-sensor --csv output
  std::string truth_csv;   ///< the recording's ground_truth.csv
  std::optional<SeedRange> random;     ///< --random: score these clips instead of a CSV
  std::optional<std::uint64_t> frames; ///< --frames: list this clip frame by frame
  unsigned jobs = 1;
  bool hanging_rest = true;  ///< the randomized world's hand rests at the arm's end; false: --floating-rest, the previous world
  bool json = false;
  bool report_only = false;  ///< --random: exit 0 even when a rate is missed
  EvaluationLimits limits;
};

/// What tachi-sensor-eval prints (to `out`; warnings to `err`) and its exit code: 0, 1 when a limit or an
/// acceptance rate is missed. Throws naming the file it cannot read.
int run_evaluation(const EvaluationOptions& options, std::ostream& out, std::ostream& err);

}  // namespace tachi::sensor
