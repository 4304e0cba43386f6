#include "tachi/sim/offline.hpp"

#include "tachi/sim/stroke.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <fstream>
#include <stdexcept>

namespace tachi::sim {
namespace {

/// SplitMix64 (Steele, Lea, Flood 2014): the same jitter on every standard library, unlike <random>'s
/// distributions, so an offline run is reproducible across compilers.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

}  // namespace

Summary run_offline(const OfflineOptions& options) {
  Session session{session_options(options)};
  Cloth& cloth = session.cloth_for_setup();
  std::uint64_t state = options.seed;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.pinned[i] != 0) continue;
    const double unit = static_cast<double>(splitmix64(state) >> 11U) * 0x1.0p-53;  // [0, 1)
    cloth.position[i].z() += options.jitter_m * static_cast<float>(2.0 * unit - 1.0);
  }
  session.set_shapes(options.spheres, options.ground);

  // The stroke is cut while stepping, each sample at its own time, through the session's
  // blade (it cuts only once its contact force reaches the blade's sharpness force).
  StrokeFile stroke;
  std::size_t stroke_outliers = 0;
  if (!options.stroke_file.empty()) {
    std::ifstream in{options.stroke_file};
    if (!in) throw std::runtime_error("cannot read " + options.stroke_file.string());
    stroke = parse_stroke_csv(in);
    for (const auto& problem : stroke.problems) spdlog::warn("{} {}; row skipped", options.stroke_file.string(), problem);
    if (stroke.skipped_rows > stroke.problems.size())
      spdlog::warn("{}: {} rows skipped in all", options.stroke_file.string(), stroke.skipped_rows);
    if (!stroke.error.empty()) throw std::runtime_error(options.stroke_file.string() + ": " + stroke.error);
    stroke_outliers = drop_impossible_samples(stroke.samples);
    if (stroke_outliers > 0)
      spdlog::warn("{}: {} samples faster than a hand (> 10 m/s) are outliers, not cut along", options.stroke_file.string(), stroke_outliers);
  }
  std::size_t next_sample = 0;

  std::vector<double> step_ms;
  step_ms.reserve(static_cast<std::size_t>(options.steps));
  const double dt = session_options(options).solver.dt;
  for (int s = 0; s < options.steps; ++s) {
    while (next_sample < stroke.samples.size() && stroke_sample_due(stroke.samples[next_sample].t, s, dt)) {
      const StrokeSample& sample = stroke.samples[next_sample++];
      session.on_hand({1, sample.t, sample.position, true, true});
      if (next_sample == stroke.samples.size()) session.end_stroke();
    }
    const auto t0 = std::chrono::steady_clock::now();
    session.step();
    step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }

  session.end_stroke();  // a stroke still open when the run ends is cut up to its last applied sample

  Summary summary = summarize(session.cloth());
  summary.steps = options.steps;
  add_cut_summary(summary, session.cloth(), session.cutter());
  add_session_summary(summary, session);
  summary.extra["stroke_samples"] = stroke.samples.size();
  summary.extra["stroke_samples_applied"] = next_sample;
  summary.extra["stroke_rows_skipped"] = stroke.skipped_rows;
  summary.extra["stroke_outliers"] = stroke_outliers;
  add_step_times(summary, step_ms);
  if (!options.export_dir.empty()) export_run(summary, session.cloth(), options.export_dir, &session.cutter());
  return summary;
}

}  // namespace tachi::sim
