// Whether a cut is a continuous function of the stroke: random hand-like strokes, the same stroke moved by
// a hair (1e-6 m), and a stroke that goes over its own cut again, each run through the offline driver
// (run_offline: the session's blade contact, the stroke cutter and the solver, as tachi-sim --offline
// --stroke). Used by the acceptance tests (tests/sim/cut_stability_test.cpp) and by the bench tool that
// runs the full 500 strokes (bench/sim/cut_stability.cpp); docs/cutting.md, "Cuts that do not flip".
#pragma once

#include "tachi/sim/offline.hpp"
#include "tachi/sim/stroke.hpp"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace tachi::sim {

/// A hand-like stroke drawn from `seed`: 60 Hz samples from t = 0.3 s along a straight line or a
/// quadratic curve between two points of the plane in front of a 1 m cloth (x, y in [-0.7, 0.7] m, so
/// it may start or end beyond the edges), at least 0.3 m apart, at 0.2-2 m/s, 0-3 cm in front (z).
[[nodiscard]] std::vector<StrokeSample> random_stroke(std::uint64_t seed);

/// The stroke with every sample moved by `metres` in a direction drawn from `seed`.
[[nodiscard]] std::vector<StrokeSample> perturbed(const std::vector<StrokeSample>& stroke, double metres,
                                                  std::uint64_t seed);

/// Forward, back and forward again along the same samples, one stroke (the hand going over its cut).
[[nodiscard]] std::vector<StrokeSample> there_back_and_there(const std::vector<StrokeSample>& stroke);

/// Writes `t,x,y,z` with every digit (17 significant), so a 1e-6 m perturbation survives the file.
void write_stroke_csv(const std::vector<StrokeSample>& stroke, const std::filesystem::path& file);

struct CutOutcome {
  std::size_t pieces = 0;
  double cut_length_m = 0.0;
  std::size_t outliers = 0;
};

/// run_offline on a top-pinned cloth of `grid` x `grid` with this stroke (written to `scratch`), blade and
/// mode, for the stroke's duration + 0.5 s.
[[nodiscard]] CutOutcome cut_outcome(const std::vector<StrokeSample>& stroke, Blade blade, CutMode mode, int grid,
                                     const std::filesystem::path& scratch);

}  // namespace tachi::sim
