// tachi-sensor-eval: compares a tachi-sensor hand CSV with a ground-truth CSV.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "tachi/common/app.hpp"
#include "tachi/sensor/hand_csv.hpp"

int main(int argc, char** argv) try {
  CLI::App app{"tachi-sensor-eval: RMS 3D palm error, tracked ratio over visible frames and phantom count"};
  app.name("tachi-sensor-eval");
  std::string hands_file, truth_file;
  bool json = false;
  double max_rms = -1, min_ratio = -1;
  long max_phantoms = -1;
  app.add_option("hands", hands_file, "tachi-sensor --csv output")->required()->check(CLI::ExistingFile);
  app.add_option("truth", truth_file, "ground truth CSV (frame,...,x,y,z,...,visible)")->required()->check(CLI::ExistingFile);
  app.add_flag("--json", json, "Print one JSON object instead of text");
  app.add_option("--max-rms-m", max_rms, "Exit 1 if the RMS 3D error exceeds this (metres)")->check(CLI::NonNegativeNumber);
  app.add_option("--min-tracked-ratio", min_ratio, "Exit 1 if the tracked ratio is below this")->check(CLI::Range(0.0, 1.0));
  app.add_option("--max-phantoms", max_phantoms, "Exit 1 if there are more phantom frames")->check(CLI::NonNegativeNumber);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;

  const auto e = tachi::sensor::evaluate(tachi::sensor::read_hand_csv(hands_file), tachi::sensor::read_truth_csv(truth_file));
  if (json) {
    std::cout << nlohmann::json{{"truth_frames", e.truth_frames}, {"missing_frames", e.missing_frames},
                                {"visible", e.visible},           {"tracked_visible", e.tracked_visible},
                                {"tracked_ratio", e.tracked_ratio}, {"phantoms", e.phantoms},
                                {"rms_m", e.rms_m},               {"median_m", e.median_m},
                                {"max_m", e.max_m}}
                     .dump()
              << '\n';
  } else {
    std::printf("frames %zu (missing %zu)\nvisible %zu, tracked %zu: tracked ratio %.4f\nphantom frames %zu\n"
                "RMS 3D error %.2f mm (median %.2f mm, max %.2f mm)\n",
                e.truth_frames, e.missing_frames, e.visible, e.tracked_visible, e.tracked_ratio, e.phantoms,
                e.rms_m * 1000, e.median_m * 1000, e.max_m * 1000);
  }
  bool ok = true;
  if (max_rms >= 0 && e.rms_m > max_rms) ok = false;
  if (min_ratio >= 0 && e.tracked_ratio < min_ratio) ok = false;
  if (max_phantoms >= 0 && static_cast<long>(e.phantoms) > max_phantoms) ok = false;
  if (e.missing_frames > 0) std::cerr << "tachi-sensor-eval: " << e.missing_frames << " ground-truth frames have no hand row\n";
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::cerr << "tachi-sensor-eval: " << e.what() << '\n';
  return 1;
}
