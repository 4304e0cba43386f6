#include "eval_cli.hpp"

#include "tachi/common/app.hpp"
#include "resting_flags.hpp"

#include <iostream>

namespace tachi::sensor {

int parse_eval_flags(int argc, char** argv, EvaluationOptions& o) {
  CLI::App app{"tachi-sensor-eval: RMS 3D palm error, tracked ratio over visible frames and phantom count; "
               "--random FIRST..LAST renders and scores randomized clips in memory"};
  app.name("tachi-sensor-eval");
  std::string range, log_level = "info";
  std::uint64_t frames_seed = 0;
  app.add_option("hands", o.hands_csv, "tachi-sensor --csv output")->check(CLI::ExistingFile);
  app.add_option("truth", o.truth_csv, "ground truth CSV (frame,...,x,y,z,...,visible)")->check(CLI::ExistingFile);
  const CLI::Validator seed_range(
      [](std::string& text) {
        return parse_seed_range(text) ? std::string{}
                                      : "expected FIRST..LAST with FIRST <= LAST (e.g. 1..1000), got \"" + text + "\"";
      },
      "FIRST..LAST");
  auto* random = app.add_option("--random", range,
                                "Render the randomized clips of seeds FIRST..LAST (tachi-synth --random), run the hand finder over "
                                "each in memory and print the distribution; exit 1 if the acceptance rates are missed")
                     ->check(seed_range);
  app.add_option("--jobs", o.jobs, "With --random: clips scored in parallel (default 1: the machine is shared)")->check(CLI::Range(1, 64));
  auto* frames = app.add_option("--frames", frames_seed, "List the randomized clip of this seed frame by frame (CSV: truth and what was tracked)");
  add_resting_flags(app, o.hanging_rest, "--random or --frames");
  app.add_flag("--report-only", o.report_only, "With --random: exit 0 even when a rate is missed");
  app.add_flag("--json", o.json, "Print one JSON object instead of text");
  app.add_option("--max-rms-m", o.limits.max_rms_m, "Exit 1 if the RMS 3D error exceeds this (metres)")->check(CLI::NonNegativeNumber);
  app.add_option("--min-tracked-ratio", o.limits.min_tracked_ratio, "Exit 1 if the tracked ratio is below this")->check(CLI::Range(0.0, 1.0));
  app.add_option("--max-phantoms", o.limits.max_phantoms, "Exit 1 if there are more phantom frames")->check(CLI::NonNegativeNumber);
  common::add_log_level_flag(app, log_level);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  common::set_log_level(log_level);
  if (frames->count() > 0) o.frames = frames_seed;
  if (random->count() > 0) {
    if (!o.hands_csv.empty()) {
      std::cerr << "tachi-sensor-eval: --random takes no CSV files\n";
      return common::kExitUsage;
    }
    o.random = parse_seed_range(range);
  } else if (!o.frames && (o.hands_csv.empty() || o.truth_csv.empty())) {
    std::cerr << "tachi-sensor-eval: give HANDS.csv TRUTH.csv, or --random FIRST..LAST\n";
    return common::kExitUsage;
  }
  return -1;
}

}  // namespace tachi::sensor
