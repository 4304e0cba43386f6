// tachi-synth: renders a scenario spec into a fakenect recording plus ground_truth.csv.
#include <iostream>

#include <spdlog/spdlog.h>

#include "tachi/common/app.hpp"
#include "tachi/sensor/synthetic.hpp"

int main(int argc, char** argv) try {
  CLI::App app{"tachi-synth: render a synthetic Kinect recording (fakenect format) and its ground truth"};
  app.name("tachi-synth");
  std::string spec_file, out_dir, log_level;
  app.add_option("--spec", spec_file, "Scenario spec (JSON), e.g. recordings/scenarios/push.json")->required()->check(CLI::ExistingFile);
  app.add_option("--out", out_dir, "Output folder (created; must not hold an INDEX.txt yet)")->required();
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(log_level);
  const auto spec = tachi::sensor::load_scenario(spec_file);
  const auto frames = tachi::sensor::write_synthetic_recording(spec, out_dir);
  spdlog::info("tachi-synth: {}: {} frames -> {}", spec.name, frames, out_dir);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "tachi-synth: " << e.what() << '\n';
  return 1;
}
