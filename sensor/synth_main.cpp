// tachi-synth: renders a scenario spec, or a randomized scene (--random SEED), into a fakenect
// recording plus ground_truth.csv.
#include <iostream>

#include <spdlog/spdlog.h>

#include "tachi/common/app.hpp"
#include "tachi/sensor/random_scene.hpp"
#include "tachi/sensor/synthetic.hpp"
#include "resting_flags.hpp"

int main(int argc, char** argv) try {
  CLI::App app{"tachi-synth: render a synthetic Kinect recording (fakenect format) and its ground truth"};
  app.name("tachi-synth");
  std::string spec_file, out_dir, log_level;
  std::uint64_t seed = 0;
  auto* spec_opt = app.add_option("--spec", spec_file, "Scenario spec (JSON), e.g. recordings/scenarios/push.json")->check(CLI::ExistingFile);
  auto* random_opt = app.add_option("--random", seed,
                                    "Render the randomized scene of this seed instead (user, room, objects, second person, hand "
                                    "path, start, Kinect noise drawn from docs/sensor.md's distributions; seeds 1-1000 tune, "
                                    "100001-100300 are held out)");
  spec_opt->excludes(random_opt);
  bool hanging_rest = true;
  tachi::sensor::add_resting_flags(app, hanging_rest, "--random", random_opt);
  app.add_option("--out", out_dir, "Output folder (created; must not hold an INDEX.txt yet)")->required();
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(log_level);
  if (spec_opt->count() == 0 && random_opt->count() == 0) {
    std::cerr << "tachi-synth: give --spec FILE or --random SEED\n";
    return 2;
  }
  const auto spec = random_opt->count() ? tachi::sensor::random_scenario(seed, hanging_rest) : tachi::sensor::load_scenario(spec_file);
  const auto frames = tachi::sensor::write_synthetic_recording(spec, out_dir);
  spdlog::info("tachi-synth: {}: {} frames -> {}", spec.name, frames, out_dir);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "tachi-synth: " << e.what() << '\n';
  return 1;
}
