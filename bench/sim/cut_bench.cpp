// Cutting benchmark (issue 4): time to apply a 64-segment stroke to a 128 x 128 cloth, target <= 0.5 ms.
// Baseline in the same process: Bullet 3.24's btSoftBody::cutLink on a 128 x 128 patch, which splits ONE
// link per call (~0.5 ms each at that size, FIELD_NOTES). Figures are medians of thread CPU time over repetitions,
// each on a fresh copy of the cloth (the copy is not timed).
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cut_line.hpp"
#include "tachi/sim/cutting.hpp"
#include "tachi/sim/pieces.hpp"
#include "tachi/sim/stroke.hpp"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
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
    const std::size_t pieces = tachi::sim::find_pieces(cloth).count();
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

}  // namespace

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::max(1, std::atoi(argv[1])) : 30;
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
  return 0;
}
