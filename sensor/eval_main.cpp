// tachi-sensor-eval: compares a tachi-sensor hand CSV with a ground-truth CSV, or (--random)
// renders and scores a range of randomized clips in memory.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <iostream>
#include <thread>

#include <nlohmann/json.hpp>

#include "tachi/common/app.hpp"
#include "tachi/sensor/clip_score.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "tachi/sensor/random_scene.hpp"

namespace {

/// "FIRST..LAST" (inclusive) or one seed.
std::pair<std::uint64_t, std::uint64_t> parse_range(const std::string& text) {
  const auto dots = text.find("..");
  try {
    std::size_t used = 0;
    if (dots == std::string::npos) {
      const auto one = std::stoull(text, &used);
      if (used == text.size()) return {one, one};
    } else {
      const auto first = std::stoull(text.substr(0, dots), &used);
      if (used == dots) {
        const auto last = std::stoull(text.substr(dots + 2), &used);
        if (used == text.size() - dots - 2 && last >= first) return {first, last};
      }
    }
  } catch (const std::exception&) {
  }
  throw CLI::ValidationError("--random", "expected FIRST..LAST with FIRST <= LAST (e.g. 1..1000), got \"" + text + "\"");
}

const char* start_name(tachi::sensor::HandStart s) {
  switch (s) {
    case tachi::sensor::HandStart::kUpFromFirstFrame: return "up";
    case tachi::sensor::HandStart::kRaisedLater: return "raised";
    case tachi::sensor::HandStart::kNeverRaised: return "never";
  }
  return "?";
}

/// One clip, frame by frame: what the finder reported against the truth.
int list_frames(std::uint64_t seed) {
  using namespace tachi::sensor;
  use_one_opencv_thread();
  const ScenarioSpec spec = random_scenario(seed);
  std::printf("frame,raised,visible,x,y,z,tracked,hx,hy,hz,error_m\n");
  score_clip(spec, {}, [](const GroundTruth& t, const HandObservation& h) {
    std::printf("%llu,%d,%d,%.4f,%.4f,%.4f,%d,%.4f,%.4f,%.4f,%.4f\n", static_cast<unsigned long long>(t.frame), t.raised ? 1 : 0,
                t.visible ? 1 : 0, t.palm.x(), t.palm.y(), t.palm.z(), h.tracked ? 1 : 0, h.position_m.x(), h.position_m.y(),
                h.position_m.z(), h.tracked ? (h.position_m.cast<double>() - t.palm).norm() : 0.0);
  });
  return 0;
}

int run_random(const std::string& range, unsigned jobs, bool json, bool report_only) {
  using namespace tachi::sensor;
  tachi::sensor::use_one_opencv_thread();
  const auto [first, last] = parse_range(range);
  const std::size_t n = static_cast<std::size_t>(last - first + 1);
  std::vector<ClipScore> clips(n);
  std::vector<ScenarioSpec> specs(n);
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < n;) {
      specs[i] = random_scenario(first + i);
      clips[i] = score_clip(specs[i]);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 1; j < std::max(1u, jobs); ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  const Summary s = summarize(clips);
  if (json) {
    nlohmann::json out;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& c = clips[i];
      out["clips"].push_back({{"seed", c.seed}, {"frames", c.frames}, {"visible", c.visible}, {"tracked_visible", c.tracked_visible},
                              {"tracked_ratio", c.tracked_ratio()}, {"rms_m", c.rms_m}, {"max_m", c.max_m}, {"phantoms", c.phantoms},
                              {"captured", c.captured}, {"longest_captured_run", c.longest_captured_run},
                              {"start", start_name(random_start(specs[i]))}});
    }
    out["summary"] = {{"clips", s.clips}, {"good_clips", s.good_clips}, {"good_share", s.good_share}, {"p50_rms_m", s.p50_rms_m},
                      {"p95_rms_m", s.p95_rms_m}, {"max_rms_m", s.max_rms_m}, {"visible", s.visible},
                      {"tracked_visible", s.tracked_visible}, {"tracked_ratio", s.tracked_ratio}, {"phantoms", s.phantoms},
                      {"captured", s.captured}, {"long_capture_clips", s.long_capture_clips},
                      {"longest_captured_run", s.longest_captured_run}, {"passed", s.passed}, {"failures", s.failures}};
    std::cout << out.dump() << '\n';
  } else {
    std::printf("%8s %6s %7s %7s %8s %8s %8s %8s %8s %7s\n", "seed", "start", "frames", "visible", "tracked", "rms_mm", "max_mm",
                "phantom", "captured", "longest");
    for (std::size_t i = 0; i < n; ++i) {
      const auto& c = clips[i];
      std::printf("%8llu %6s %7zu %7zu %7.1f%% %8.2f %8.2f %8zu %8zu %7zu\n", static_cast<unsigned long long>(c.seed),
                  start_name(random_start(specs[i])), c.frames, c.visible, 100 * c.tracked_ratio(), c.rms_m * 1000, c.max_m * 1000,
                  c.phantoms, c.captured, c.longest_captured_run);
    }
    std::printf("\nseeds %llu..%llu: %zu clips\n", static_cast<unsigned long long>(first), static_cast<unsigned long long>(last), s.clips);
    std::printf("clips with RMS <= 1 cm: %zu (%.1f%%); per-clip RMS p50 %.2f mm, p95 %.2f mm, max %.2f mm\n", s.good_clips,
                100 * s.good_share, s.p50_rms_m * 1000, s.p95_rms_m * 1000, s.max_rms_m * 1000);
    std::printf("visible frames tracked: %zu of %zu (%.2f%%)\n", s.tracked_visible, s.visible, 100 * s.tracked_ratio);
    std::printf("phantom frames: %zu (in %zu clips)\n", s.phantoms, s.phantom_clips);
    std::printf("captured frames: %zu (in %zu clips); longest captured run %zu; clips with a run > 3: %zu\n", s.captured,
                s.captured_clips, s.longest_captured_run, s.long_capture_clips);
    std::printf("%s\n", s.passed ? "PASS (the acceptance rates)" : "FAIL (the acceptance rates):");
    for (const auto& f : s.failures) std::printf("  %s\n", f.c_str());
  }
  return s.passed || report_only ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-sensor-eval: RMS 3D palm error, tracked ratio over visible frames and phantom count; "
               "--random FIRST..LAST renders and scores randomized clips in memory"};
  app.name("tachi-sensor-eval");
  std::string hands_file, truth_file, range;
  bool json = false, report_only = false;
  std::uint64_t frames_seed = 0;
  unsigned jobs = 1;
  double max_rms = -1, min_ratio = -1;
  long max_phantoms = -1;
  app.add_option("hands", hands_file, "tachi-sensor --csv output")->check(CLI::ExistingFile);
  app.add_option("truth", truth_file, "ground truth CSV (frame,...,x,y,z,...,visible)")->check(CLI::ExistingFile);
  auto* random = app.add_option("--random", range,
                                "Render the randomized clips of seeds FIRST..LAST (tachi-synth --random), run the hand finder over "
                                "each in memory and print the distribution; exit 1 if the acceptance rates are missed");
  app.add_option("--jobs", jobs, "With --random: clips scored in parallel (default 1: the machine is shared)")->check(CLI::Range(1, 64));
  auto* frames_opt = app.add_option("--frames", frames_seed, "List one randomized clip frame by frame (CSV: truth and what was tracked)");
  app.add_flag("--report-only", report_only, "With --random: exit 0 even when a rate is missed");
  app.add_flag("--json", json, "Print one JSON object instead of text");
  app.add_option("--max-rms-m", max_rms, "Exit 1 if the RMS 3D error exceeds this (metres)")->check(CLI::NonNegativeNumber);
  app.add_option("--min-tracked-ratio", min_ratio, "Exit 1 if the tracked ratio is below this")->check(CLI::Range(0.0, 1.0));
  app.add_option("--max-phantoms", max_phantoms, "Exit 1 if there are more phantom frames")->check(CLI::NonNegativeNumber);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  if (frames_opt->count() > 0) return list_frames(frames_seed);
  if (random->count() > 0) {
    if (!hands_file.empty()) {
      std::cerr << "tachi-sensor-eval: --random takes no CSV files\n";
      return 2;
    }
    return run_random(range, jobs, json, report_only);
  }
  if (hands_file.empty() || truth_file.empty()) {
    std::cerr << "tachi-sensor-eval: give HANDS.csv TRUTH.csv, or --random FIRST..LAST\n";
    return 2;
  }

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
} catch (const CLI::Error& e) {
  std::cerr << "tachi-sensor-eval: " << e.what() << '\n';
  return 2;
} catch (const std::exception& e) {
  std::cerr << "tachi-sensor-eval: " << e.what() << '\n';
  return 1;
}
