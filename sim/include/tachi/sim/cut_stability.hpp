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
#include <string>
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

/// The 1/60 s steps cut_outcome simulates for a stroke: its duration + 0.5 s.
[[nodiscard]] int offline_steps(const std::vector<StrokeSample>& stroke);

/// run_offline on a top-pinned cloth of `grid` x `grid` with this stroke (written to `scratch`), blade and
/// mode, for the stroke's duration + 0.5 s.
[[nodiscard]] CutOutcome cut_outcome(const std::vector<StrokeSample>& stroke, Blade blade, CutMode mode, int grid,
                                     const std::filesystem::path& scratch);

/// The blade table of docs/cutting.md ("Blade sharpness decides the cut"), as markdown rows: for each
/// blade, three strokes on a 64 x 64 cloth hanging from its top edge, 420 steps, grid mode (2 cm in front,
/// 60 Hz, from t = 0.5 s): across at y = 0 from x = -0.7 to 0.7 m in 6 s and in 2 s, and a 20 cm push along
/// the free bottom edge at y = -0.45 m in 6 s; each "cut m / drag mm / pieces". `cut_stability
/// --blade-table` prints it; a test compares it with the doc. `scratch` is where the strokes are written.
[[nodiscard]] std::string blade_table(const std::filesystem::path& scratch);

}  // namespace tachi::sim
