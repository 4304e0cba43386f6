#include "tachi/sensor/evaluation.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <thread>

namespace tachi::sensor {
namespace {

// printf into a stream: the report's columns are printf formats.
void print(std::ostream& out, const char* format, ...) __attribute__((format(printf, 2, 3)));
void print(std::ostream& out, const char* format, ...) {
  char line[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(line, sizeof line, format, args);
  va_end(args);
  out << line;
}

unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }

void list_frames(std::uint64_t seed, bool hanging_rest, std::ostream& out) {
  use_one_opencv_thread();
  const ScenarioSpec spec = random_scenario(seed, hanging_rest);
  out << "frame,raised,visible,x,y,z,tracked,hx,hy,hz,error_m\n";
  score_clip(spec, {}, [&out](const GroundTruth& t, const HandObservation& h) {
    print(out, "%llu,%d,%d,%.4f,%.4f,%.4f,%d,%.4f,%.4f,%.4f,%.4f\n", ull(t.frame), t.raised ? 1 : 0, t.visible ? 1 : 0,
          t.palm.x(), t.palm.y(), t.palm.z(), h.tracked ? 1 : 0, h.position_m.x(), h.position_m.y(), h.position_m.z(),
          h.tracked ? (h.position_m.cast<double>() - t.palm).norm() : 0.0);
  });
}

void print_random_json(const RandomRun& run, std::ostream& out) {
  nlohmann::json json;
  for (std::size_t i = 0; i < run.clips.size(); ++i) {
    const auto& c = run.clips[i];
    json["clips"].push_back({{"seed", c.seed}, {"frames", c.frames}, {"visible", c.visible}, {"tracked_visible", c.tracked_visible},
                             {"tracked_ratio", c.tracked_ratio()}, {"rms_m", c.rms_m}, {"max_m", c.max_m}, {"phantoms", c.phantoms},
                             {"captured", c.captured}, {"longest_captured_run", c.longest_captured_run},
                             {"start", start_name(random_start(run.specs[i]))}});
  }
  const Summary& s = run.summary;
  json["summary"] = {{"clips", s.clips}, {"good_clips", s.good_clips}, {"good_share", s.good_share}, {"p50_rms_m", s.p50_rms_m},
                     {"p95_rms_m", s.p95_rms_m}, {"max_rms_m", s.max_rms_m}, {"visible", s.visible},
                     {"tracked_visible", s.tracked_visible}, {"tracked_ratio", s.tracked_ratio}, {"phantoms", s.phantoms},
                     {"captured", s.captured}, {"long_capture_clips", s.long_capture_clips},
                     {"longest_captured_run", s.longest_captured_run}, {"passed", s.passed}, {"failures", s.failures}};
  out << json.dump() << '\n';
}

void print_random_text(const RandomRun& run, std::ostream& out) {
  print(out, "%8s %6s %7s %7s %8s %8s %8s %8s %8s %7s\n", "seed", "start", "frames", "visible", "tracked", "rms_mm", "max_mm",
        "phantom", "captured", "longest");
  for (std::size_t i = 0; i < run.clips.size(); ++i) {
    const auto& c = run.clips[i];
    print(out, "%8llu %6s %7zu %7zu %7.1f%% %8.2f %8.2f %8zu %8zu %7zu\n", ull(c.seed), start_name(random_start(run.specs[i])),
          c.frames, c.visible, 100 * c.tracked_ratio(), c.rms_m * 1000, c.max_m * 1000, c.phantoms, c.captured,
          c.longest_captured_run);
  }
  const Summary& s = run.summary;
  print(out, "\nseeds %llu..%llu: %zu clips\n", ull(run.seeds.first), ull(run.seeds.last), s.clips);
  print(out, "clips with RMS <= 1 cm: %zu (%.1f%%); per-clip RMS p50 %.2f mm, p95 %.2f mm, max %.2f mm\n", s.good_clips,
        100 * s.good_share, s.p50_rms_m * 1000, s.p95_rms_m * 1000, s.max_rms_m * 1000);
  print(out, "visible frames tracked: %zu of %zu (%.2f%%)\n", s.tracked_visible, s.visible, 100 * s.tracked_ratio);
  print(out, "phantom frames: %zu (in %zu clips)\n", s.phantoms, s.phantom_clips);
  print(out, "captured frames: %zu (in %zu clips); longest captured run %zu; clips with a run > 3: %zu\n", s.captured,
        s.captured_clips, s.longest_captured_run, s.long_capture_clips);
  out << (s.passed ? "PASS (the acceptance rates)" : "FAIL (the acceptance rates):") << '\n';
  for (const auto& f : s.failures) out << "  " << f << '\n';
}

void print_evaluation(const Evaluation& e, bool json, std::ostream& out) {
  if (json) {
    out << nlohmann::json{{"truth_frames", e.truth_frames}, {"missing_frames", e.missing_frames},
                          {"visible", e.visible},           {"tracked_visible", e.tracked_visible},
                          {"tracked_ratio", e.tracked_ratio}, {"phantoms", e.phantoms},
                          {"rms_m", e.rms_m},               {"median_m", e.median_m},
                          {"max_m", e.max_m}}
               .dump()
        << '\n';
    return;
  }
  print(out, "frames %zu (missing %zu)\nvisible %zu, tracked %zu: tracked ratio %.4f\nphantom frames %zu\n"
             "RMS 3D error %.2f mm (median %.2f mm, max %.2f mm)\n",
        e.truth_frames, e.missing_frames, e.visible, e.tracked_visible, e.tracked_ratio, e.phantoms, e.rms_m * 1000,
        e.median_m * 1000, e.max_m * 1000);
}
}  // namespace

std::optional<SeedRange> parse_seed_range(const std::string& text) {
  const auto dots = text.find("..");
  const auto number = [](const std::string& digits) -> std::optional<std::uint64_t> {
    if (digits.empty() || !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); }))
      return std::nullopt;
    try {
      return std::stoull(digits);
    } catch (const std::out_of_range&) {
      return std::nullopt;
    }
  };
  if (dots == std::string::npos) {
    if (const auto one = number(text)) return SeedRange{*one, *one};
    return std::nullopt;
  }
  const auto first = number(text.substr(0, dots));
  const auto last = number(text.substr(dots + 2));
  if (!first || !last || *last < *first) return std::nullopt;
  return SeedRange{*first, *last};
}

RandomRun score_random(SeedRange seeds, unsigned jobs, bool hanging_rest) {
  use_one_opencv_thread();
  RandomRun run;
  run.seeds = seeds;
  const auto n = static_cast<std::size_t>(seeds.last - seeds.first + 1);
  run.clips.resize(n);
  run.specs.resize(n);
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < n;) {
      run.specs[i] = random_scenario(seeds.first + i, hanging_rest);
      run.clips[i] = score_clip(run.specs[i]);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 1; j < std::max(1U, jobs); ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  run.summary = summarize(run.clips);
  return run;
}

const char* start_name(HandStart start) {
  switch (start) {
    case HandStart::kUpFromFirstFrame: return "up";
    case HandStart::kRaisedLater: return "raised";
    case HandStart::kNeverRaised: return "never";
  }
  return "?";
}

bool EvaluationLimits::met(const Evaluation& e) const {
  if (max_rms_m >= 0 && e.rms_m > max_rms_m) return false;
  if (min_tracked_ratio >= 0 && e.tracked_ratio < min_tracked_ratio) return false;
  return !(max_phantoms >= 0 && static_cast<long>(e.phantoms) > max_phantoms);
}

int run_evaluation(const EvaluationOptions& o, std::ostream& out, std::ostream& err) {
  if (o.frames) {
    list_frames(*o.frames, o.hanging_rest, out);
    return 0;
  }
  if (o.random) {
    const RandomRun run = score_random(*o.random, o.jobs, o.hanging_rest);
    if (o.json) print_random_json(run, out);
    else print_random_text(run, out);
    return run.summary.passed || o.report_only ? 0 : 1;
  }
  const auto e = evaluate(read_hand_csv(o.hands_csv), read_truth_csv(o.truth_csv));
  print_evaluation(e, o.json, out);
  if (e.missing_frames > 0) err << "tachi-sensor-eval: " << e.missing_frames << " ground-truth frames have no hand row\n";
  return o.limits.met(e) ? 0 : 1;
}

}  // namespace tachi::sensor
