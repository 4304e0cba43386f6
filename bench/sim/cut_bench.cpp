// Cutting benchmark: time to apply a 64-segment stroke to a 128 x 128 cloth, target <= 0.5 ms.
// Baseline in the same process: Bullet 3.24's btSoftBody::cutLink on a 128 x 128 patch, which splits ONE
// link per call (~0.5 ms each at that size, FIELD_NOTES). Figures are medians of thread CPU time over repetitions,
// each on a fresh copy of the cloth (the copy is not timed).
#include "../bench_args.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cut_line.hpp"
#include "tachi/sim/cutting.hpp"
#include "tachi/sim/pieces.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

namespace {

using tachi::sim::Cloth;

/// CPU time of this thread, ms: the machine is shared, and time spent descheduled is not the code's.
double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double ms_since(double t0) { return cpu_ms() - t0; }

/// Wall time, ms: on several threads the main thread's CPU time misses the others' work.
double wall_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// 65 samples (64 segments) of a wavy stroke from beyond the left edge to beyond the right one, world metres.
std::vector<tachi::sim::StrokeSample> wavy_stroke() {
  std::vector<tachi::sim::StrokeSample> out;
  for (int i = 0; i <= 64; ++i) {
    const double s = i / 64.0;
    const double x = -0.52 + 1.04 * s;
    const double y = -0.05 + 0.2 * std::sin(2.0 * 3.14159265358979 * 1.5 * s);
    out.push_back({s, Eigen::Vector3f{static_cast<float>(x), static_cast<float>(y), 0.01F}});
  }
  return out;
}

/// 65 samples of a straight stroke across the cloth, slightly slanted, beyond both edges.
std::vector<tachi::sim::StrokeSample> straight_stroke() {
  std::vector<tachi::sim::StrokeSample> out;
  for (int i = 0; i <= 64; ++i) {
    const double s = i / 64.0;
    out.push_back({s, Eigen::Vector3f{static_cast<float>(-0.52 + 1.04 * s), static_cast<float>(0.1 - 0.1 * s), 0.01F}});
  }
  return out;
}

/// What applying a stroke to fresh copies of a cloth gave, and how long it took (median).
struct StrokeRun {
  double median_ms = 0.0;
  std::vector<tachi::sim::GridCoord> line;
  std::size_t duplicated = 0;
  std::size_t pieces = 0;
  double pieces_ms = 0.0;  ///< find_pieces afterwards, median
};

StrokeRun time_stroke(const Cloth& prototype, const std::vector<tachi::sim::StrokeSample>& stroke, int reps) {
  StrokeRun run;
  std::vector<double> ms;
  std::vector<double> pieces_ms;
  for (int r = 0; r < reps; ++r) {
    Cloth cloth = prototype;
    tachi::sim::StrokeCutter cutter{cloth, {}};
    const auto t0 = cpu_ms();
    for (const auto& s : stroke) cutter.add_sample(s);
    cutter.end_stroke();
    ms.push_back(ms_since(t0));
    const auto t1 = cpu_ms();
    const std::size_t pieces = tachi::sim::find_pieces(cloth).cloth_count();
    pieces_ms.push_back(ms_since(t1));
    if (r > 0 && (pieces != run.pieces || cutter.report().cut_line.size() != run.line.size())) std::abort();
    run.line = cutter.report().cut_line;
    run.duplicated = cutter.report().particles_duplicated;
    run.pieces = pieces;
  }
  run.median_ms = median(ms);
  run.pieces_ms = median(pieces_ms);
  return run;
}

/// Exact mode: the stroke cut at once on a cloth whose solver is warm, then the steps after it.
struct ExactRun {
  double stroke_ms = 0.0;      ///< median: locate, simplify, split triangles, separate, springs
  double update_ms = 0.0;      ///< median: the solver's update after the cut (Solver::update_topology)
  double step_ms = 0.0;        ///< median step (no cut)
  double after_cut_ms = 0.0;   ///< median: the step right after the cut, its update included
  /// median over reps of the worst step after that one while the cut's work and repair go on (and 2 more):
  /// a cut's work spread over steps (SolverParams::cut_work_per_step) must not move the spike, only cut it
  double worst_following_ms = 0.0;
  std::size_t following_steps = 0;  ///< median count of those steps
  /// median: a plain step of the cut cloth once the cut's work and repairs are over (its particles, springs
  /// and tethers make every step after a cut dearer than the uncut cloth's; not the acceptance's baseline)
  double cut_cloth_step_ms = 0.0;
  std::size_t particles = 0;
  std::size_t pieces = 0;
  double deviation = 0.0;
  std::size_t full_builds = 0;
};

ExactRun time_exact(const Cloth& prototype, const std::vector<tachi::sim::StrokeSample>& stroke,
                    tachi::sim::CutMode mode, int reps, const tachi::sim::SolverParams& params) {
  ExactRun run;
  // On several threads the main thread's CPU time misses the others' work: wall time then.
  const auto now = params.threads > 1 ? wall_ms : cpu_ms;
  std::vector<double> stroke_ms;
  std::vector<double> after_ms;
  std::vector<double> update_ms;
  std::vector<double> step_ms;
  std::vector<double> worst_following_ms;
  std::vector<double> following_steps;
  std::vector<double> cut_cloth_ms;
  for (int r = 0; r < reps; ++r) {
    // As tachi-sim runs: the cutter reserves the cloth's room for cuts, then the solver's first step builds
    // its caches with that room (not timed). A copy of a warm solver would not do: a vector's copy drops
    // its reserved capacity, so the first cut would reallocate every per-particle array of the copy.
    Cloth cloth = prototype;
    tachi::sim::StrokeOptions options;
    options.mode = mode;
    tachi::sim::StrokeCutter cutter{cloth, options};
    tachi::sim::Solver solver{params};
    solver.step(cloth);
    for (int s = 0; s < 3; ++s) {  // plain steps, for the median
      const auto t0 = now();
      solver.step(cloth);
      step_ms.push_back(now() - t0);
    }
    const auto t0 = now();
    for (const auto& s : stroke) cutter.add_sample(s);
    cutter.end_stroke();
    stroke_ms.push_back(now() - t0);
    const auto t2 = now();
    solver.update_topology(cloth);
    update_ms.push_back(now() - t2);
    const auto t1 = now();
    solver.step(cloth);
    after_ms.push_back(now() - t1 + update_ms.back());
    double worst = 0.0;
    int following = 0;
    for (int tail = 0; tail < 2 && following < 200; ++following) {
      if (!solver.repairing()) ++tail;
      const auto t3 = now();
      solver.step(cloth);
      worst = std::max(worst, now() - t3);
    }
    worst_following_ms.push_back(worst);
    following_steps.push_back(following);
    for (int s = 0; s < 3; ++s) {
      const auto t4 = now();
      solver.step(cloth);
      cut_cloth_ms.push_back(now() - t4);
    }
    run.particles = cloth.particle_count();
    run.pieces = tachi::sim::find_pieces(cloth).cloth_count();
    run.deviation = cutter.exact() != nullptr ? cutter.exact()->max_deviation_cells() : 0.0;
    run.full_builds = solver.full_builds();
  }
  run.stroke_ms = median(stroke_ms);
  run.step_ms = median(step_ms);
  run.after_cut_ms = median(after_ms);
  run.update_ms = median(update_ms);
  run.worst_following_ms = median(worst_following_ms);
  run.following_steps = static_cast<std::size_t>(median(following_steps));
  run.cut_cloth_step_ms = median(cut_cloth_ms);
  return run;
}

/// A long stroke (2 s, 120 samples, across and down) cut progressively on an N x N cloth while it steps:
/// the worst frame (samples of the frame + the step), the first excepted (reported apart), and the median.
struct LiveRun {
  double worst_cut_ms = 0.0;   ///< the samples of one frame (locate, cut)
  double worst_step_ms = 0.0;  ///< one step (with the solver's update after a cut)
  double worst_ms = 0.0;
  double median_ms = 0.0;
  double first_ms = 0.0;
  double build_ms = 0.0;  ///< the solver's construction with the cloth (its caches' full build)
  std::size_t pieces = 0;
  std::size_t full_builds = 0;
  int worst_step_at = 0;
  float max_strain = 0.0F;      ///< structural, at the end (the cut-off piece is falling by then)
  std::size_t overstretched = 0;  ///< structural springs over Provot's 10 % at the end
  float peak_strain = 0.0F;     ///< structural, the most after any step (checked outside the timed frames)
  std::size_t most_over_half = 0;  ///< the most structural springs over 50 % after one step
  std::size_t most_over_fifth = 0;  ///< the most structural springs over 20 % after one step
};

LiveRun time_long_stroke(int n, tachi::sim::CutMode mode, const tachi::sim::SolverParams& params, bool wall) {
  tachi::sim::ClothConfig config;
  config.columns = n;
  config.rows = n;
  config.pin = tachi::sim::PinMode::TopEdge;
  Cloth cloth{config};
  tachi::sim::StrokeOptions options;
  options.mode = mode;
  tachi::sim::StrokeCutter cutter{cloth, options};
  // Built with the cloth, after the cutter reserved its room for cuts: the first step is an ordinary one.
  const double build_start = wall ? wall_ms() : cpu_ms();
  tachi::sim::Solver solver{cloth, params};
  LiveRun run;
  run.build_ms = (wall ? wall_ms() : cpu_ms()) - build_start;
  std::vector<double> frame_ms;
  constexpr int kSteps = 240;
  // The thread's CPU time (the machine is shared), or wall time, what a frame takes (threads given: the
  // other threads' work is not in this one's CPU time).
  const auto now = [&] { return wall ? wall_ms() : cpu_ms(); };
  const auto ms_since = [&](double t0) { return now() - t0; };
  for (int s = 0; s < kSteps; ++s) {
    const auto t0 = now();
    if (s >= 30 && s <= 150) {
      const double u = (s - 30) / 120.0;
      const float x = static_cast<float>(-0.55 + 1.1 * u);
      const float y = static_cast<float>(0.3 - 0.5 * u + 0.1 * std::sin(6.0 * u));
      cutter.add_sample({s / 60.0, Eigen::Vector3f{x, y, 0.0F}});
      if (s == 150) cutter.end_stroke();
    }
    const double cut_ms = ms_since(t0);
    const auto t1 = now();
    solver.step(cloth);
    const double ms = ms_since(t0);
    if (s > 0) {
      run.worst_cut_ms = std::max(run.worst_cut_ms, cut_ms);
      if (ms_since(t1) > run.worst_step_ms) {
        run.worst_step_ms = ms_since(t1);
        run.worst_step_at = s;
      }
    }
    if (s == 0) {
      run.first_ms = ms;
    } else {
      frame_ms.push_back(ms);
    }
    // While the stroke goes on the cloth below it stretches (docs/sim.md, "Limits"): how much, after each step.
    std::size_t over_half = 0;
    std::size_t over_fifth = 0;
    for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
      if (cloth.alive[k] == 0 || cloth.kind[k] != tachi::sim::SpringKind::Structural) continue;
      const float strain =
          (cloth.position[cloth.spring_a[k]] - cloth.position[cloth.spring_b[k]]).norm() / cloth.rest_length[k] - 1.0F;
      run.peak_strain = std::max(run.peak_strain, strain);
      if (strain > 0.5F) ++over_half;
      if (strain > 0.2F) ++over_fifth;
    }
    run.most_over_half = std::max(run.most_over_half, over_half);
    run.most_over_fifth = std::max(run.most_over_fifth, over_fifth);
  }
  run.worst_ms = *std::max_element(frame_ms.begin(), frame_ms.end());
  run.median_ms = median(frame_ms);
  run.pieces = tachi::sim::find_pieces(cloth).cloth_count();
  run.full_builds = solver.full_builds();
  // How the cloth came out of it, not only how fast: a repair of the attachments that cannot keep up with
  // the stroke leaves the cloth below the cut without tethers, and it stretches (docs/sim.md, "Limits").
  run.max_strain = cloth.max_structural_strain();
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] != tachi::sim::SpringKind::Structural) continue;
    const float length = (cloth.position[cloth.spring_a[k]] - cloth.position[cloth.spring_b[k]]).norm();
    if (length > 1.1F * cloth.rest_length[k]) ++run.overstretched;
  }
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  // cut_bench [reps] [repair_per_step] [threads] [substeps] [cut_work_per_step] [long_cut_work_per_step]: the second argument sets the
  // long strokes' attachment repair budget (SolverParams::repair_per_step, 0 for the default) for the measurements in docs/sim.md
  // ("Limits"); the third and fourth their solver's threads (given: the frames are timed in wall time) and
  // sub-steps (the third also the exact section's threads); the fifth the exact section's
  // SolverParams::cut_work_per_step (default: the solver's, 1 since 2026-12-05; the figures measured before
  // it without these arguments are 0's); the sixth the long strokes' (default: the solver's).
  const char* usage =
      "usage: cut_bench [REPS=30] [REPAIR_PER_STEP=0: the solver's] [THREADS=1] [SUBSTEPS=2] [CUT_WORK_PER_STEP=1] "
      "[LONG_CUT_WORK_PER_STEP=1]\n(docs/benchmarks.md; e.g. `cut_bench 5 0 2 2`: two threads)\n";
  tachi::bench::exit_on_help(argc, argv, usage);
  const auto arg = [&](int i, int min, int max) { return tachi::bench::int_argument(argv[i], "cut_bench", min, max, usage); };
  if (argc > 7) {
    std::fprintf(stderr, "cut_bench: at most six arguments\n%s", usage);
    return 2;
  }
  const int reps = argc > 1 ? arg(1, 1, 100000) : 30;
  tachi::sim::SolverParams long_stroke_params;
  // 0: the solver's default (one budget for all pin groups since session 27; 2048 per group before).
  if (const int repair = argc > 2 ? arg(2, 0, 1 << 30) : 0; repair > 0) long_stroke_params.repair_per_step = repair;
  if (argc > 3) long_stroke_params.threads = arg(3, 1, 64);
  if (argc > 4) long_stroke_params.substeps = arg(4, 1, 64);
  tachi::sim::SolverParams exact_params;
  if (argc > 5) exact_params.cut_work_per_step = arg(5, 0, 1 << 30);
  if (argc > 6) long_stroke_params.cut_work_per_step = arg(6, 0, 1 << 30);
  exact_params.threads = long_stroke_params.threads;  // the target is for one thread and two
  constexpr int n = 128;
  tachi::sim::ClothConfig config;
  config.columns = n;
  config.rows = n;
  config.pin = tachi::sim::PinMode::TopEdge;
  const Cloth prototype{config};

  const StrokeRun wavy = time_stroke(prototype, wavy_stroke(), reps);
  const StrokeRun straight = time_stroke(prototype, straight_stroke(), reps);
  // The wavy stroke's cut line through the topological cut alone.
  std::vector<double> cut_ms;
  for (int r = 0; r < reps; ++r) {
    Cloth cloth = prototype;
    tachi::sim::ClothCutter cutter{cloth};
    const auto t0 = cpu_ms();
    cutter.cut(wavy.line);
    cut_ms.push_back(ms_since(t0));
  }

  // Bullet baseline: cutLink across the vertical links under one row of a 128 x 128 patch.
  btSoftBodyWorldInfo info;
  info.m_gravity.setValue(0.0F, -9.81F, 0.0F);
  info.m_sparsesdf.Initialize();
  constexpr int bullet_edges = 24;
  std::vector<double> bullet_ms;
  double bullet_first_ms = 0.0;
  {
    std::unique_ptr<btSoftBody> patch{btSoftBodyHelpers::CreatePatch(info, btVector3(-0.5, 0.5, 0), btVector3(0.5, 0.5, 0),
                                                                     btVector3(-0.5, -0.5, 0), btVector3(0.5, -0.5, 0), n,
                                                                     n, 1 + 2, true)};
    const int row = n / 2;
    for (int i = 0; i <= bullet_edges; ++i) {
      const int x = 20 + i;
      const auto t0 = cpu_ms();
      const bool ok = patch->cutLink(row * n + x, (row + 1) * n + x, 0.5);
      const double ms = ms_since(t0);
      if (!ok) std::fprintf(stderr, "cut_bench: Bullet cutLink refused link %d\n", x);
      if (i == 0) {
        bullet_first_ms = ms;  // first call builds caches: reported apart
      } else {
        bullet_ms.push_back(ms);
      }
    }
  }

  const double stroke_median = wavy.median_ms;
  const double cut_median = median(cut_ms);
  const double bullet_median = median(bullet_ms);
  const std::size_t edges = wavy.line.empty() ? 0 : wavy.line.size() - 1;
  std::printf("cut_bench: %dx%d cloth, wavy 64-segment stroke -> %zu cut-line particles, %zu duplicated, %zu pieces, %d reps\n",
              n, n, wavy.line.size(), wavy.duplicated, wavy.pieces, reps);
  std::printf("  wavy stroke, whole pipeline (locate, simplify, rasterise, cut, drag): median %.3f ms  (target <= 0.5 ms)\n",
              stroke_median);
  std::printf("  straight stroke across (%zu cut-line particles), whole pipeline:     median %.3f ms  (target <= 0.5 ms)\n",
              straight.line.size(), straight.median_ms);
  std::printf("  wavy line, topological cut alone:                                    median %.3f ms  = %.2f us per cut edge\n",
              cut_median, 1000.0 * cut_median / static_cast<double>(std::max<std::size_t>(edges, 1)));
  std::printf("  pieces (union-find over all springs, once per stroke):               median %.3f ms\n", wavy.pieces_ms);
  std::printf("  Bullet btSoftBody::cutLink, one link:                                median %.3f ms  (first call %.1f ms)\n",
              bullet_median, bullet_first_ms);
  std::printf("  ratio per cut edge, Bullet / ours: %.0fx; whole stroke (%zu edges) vs Bullet at %zu links: %.0fx\n",
              bullet_median / (cut_median / static_cast<double>(std::max<std::size_t>(edges, 1))), edges, edges,
              bullet_median * static_cast<double>(edges) / stroke_median);

  // Exact mode, with the solver's incremental update, against the grid mode in the same process.
  std::printf("exact cut, %dx%d, wavy 64-segment stroke cut at once after a first step, %d reps, cut_work_per_step %d, "
              "%d thread(s) (%s time):\n",
              n, n, reps, exact_params.cut_work_per_step, exact_params.threads, exact_params.threads > 1 ? "wall" : "CPU");
  for (const auto mode : {tachi::sim::CutMode::Exact, tachi::sim::CutMode::Grid, tachi::sim::CutMode::Delete}) {
    const ExactRun e = time_exact(prototype, wavy_stroke(), mode, reps, exact_params);
    std::printf("  %-6s stroke %.3f ms + solver update %.3f ms = %.3f ms (target <= 0.5 ms); step after cut %.3f ms / "
                "median step %.3f ms = %.2fx (target <= 1.5x); worst of the %zu steps after it %.3f ms = %.2fx; "
                "the cut cloth's plain step afterwards %.3f ms (%.2fx the uncut one; the step after the cut %.2fx it); "
                "%zu particles, %zu pieces, deviation %.3f cells, full builds %zu\n",
                std::string{tachi::sim::to_string(mode)}.c_str(), e.stroke_ms, e.update_ms, e.stroke_ms + e.update_ms,
                e.after_cut_ms, e.step_ms, e.after_cut_ms / e.step_ms, e.following_steps, e.worst_following_ms,
                e.worst_following_ms / e.step_ms, e.cut_cloth_step_ms, e.cut_cloth_step_ms / e.step_ms,
                e.after_cut_ms / e.cut_cloth_step_ms, e.particles, e.pieces, e.deviation, e.full_builds);
  }
  for (const int size : {128, 256}) {
    // Delete too: the long-stroke targets are for every mode, and delete cuts otherwise (the triangles the
    // blade passes through removed), so exact's and grid's figures do not stand for it.
    for (const auto mode : {tachi::sim::CutMode::Exact, tachi::sim::CutMode::Grid, tachi::sim::CutMode::Delete}) {
      const LiveRun l = time_long_stroke(size, mode, long_stroke_params, argc > 3);
      std::printf("  %dx%d %-6s long stroke cut while stepping: worst frame %.2f ms (target <= 16 ms; worst cut %.2f ms, "
                  "worst step %.2f ms at step %d), median %.2f ms, first step %.2f ms = %.1fx the median (target <= 2x; the "
                  "solver's build at construction %.2f ms), %zu pieces, %zu full builds; "
                  "at the end max strain %.1f %%, %zu structural springs over 10 %%; during it peak strain %.0f %%, "
                  "at most %zu over 50 %%, %zu over 20 %% (%d threads, %d sub-steps, %s time)\n",
                  size, size, std::string{tachi::sim::to_string(mode)}.c_str(), l.worst_ms, l.worst_cut_ms,
                  l.worst_step_ms, l.worst_step_at, l.median_ms, l.first_ms, l.first_ms / l.median_ms, l.build_ms, l.pieces,
                  l.full_builds,
                  100.0 * static_cast<double>(l.max_strain), l.overstretched, 100.0 * static_cast<double>(l.peak_strain),
                  l.most_over_half, l.most_over_fifth, long_stroke_params.threads, long_stroke_params.substeps,
                  argc > 3 ? "wall" : "CPU");
    }
  }
  return 0;
}
