// provot_bench: Provot's explicit mass-spring scheme (--solver provot) against the default
// position-based solver on the same grid and material, in one process: cost per step (median, and the
// ratio to PBD measured alongside), strain and sag after settling, stability over the sub-step count and
// time step, and what one cut does. Figures and the command: docs/sim.md and docs/benchmarks.md.
#include "../bench_args.hpp"
#include "tachi/sim/cloth_solver.hpp"
#include "tachi/sim/material.hpp"
#include "tachi/sim/session.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using namespace tachi::sim;

struct Run {
  double step_ms = 0.0;  ///< median over the timed steps
  float strain = 0.0F;   ///< max structural strain at the end
  float sag_m = 0.0F;    ///< drop of the top edge's middle below the pinned corners
  float fastest = 0.0F;  ///< fastest particle at the end, m/s
  bool finite = true;
};

SessionOptions options(SolverKind kind, int grid, float dt, int substeps, const Material& material) {
  SessionOptions o;
  o.cloth.columns = o.cloth.rows = grid;
  o.solver.dt = dt;
  o.solver_kind = kind;
  o.material = material;
  apply_material(material, o.cloth, o.solver);
  o.solver.substeps = substeps;
  o.provot.substeps = substeps;
  return o;
}

Run hang(const SessionOptions& o, double seconds) {
  Session session{o};
  const int steps = static_cast<int>(seconds / o.solver.dt);
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    session.step();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(ms.size() / 2), ms.end());
  const Cloth& c = session.cloth();
  Run r;
  r.step_ms = ms[ms.size() / 2];
  r.strain = c.max_structural_strain();
  r.sag_m = c.position[c.index(0, 0)].y() - c.position[c.index(c.columns / 2, 0)].y();
  for (std::size_t i = 0; i < c.particle_count(); ++i) {
    r.finite = r.finite && c.position[i].allFinite();
    r.fastest = std::max(r.fastest, c.velocity[i].norm());
  }
  return r;
}

/// Blown up: non-finite or flying apart; otherwise whether Provot's 10 % strain limit holds.
const char* verdict(const Run& r) {
  if (!r.finite || r.fastest > 5.0F) return "BLOWS UP";
  return r.strain <= 0.101F ? "stable, strain <= 10 %" : "stable, strain OVER 10 %";
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: provot_bench [GRID=64]   (particles per side, 4..512; docs/sim.md, docs/benchmarks.md)\n";
  tachi::bench::exit_on_help(argc, argv, usage);
  if (argc > 2) {
    std::fprintf(stderr, "provot_bench: one argument at most\n%s", usage);
    return 2;
  }
  const int grid = argc > 1 ? tachi::bench::int_argument(argv[1], "provot_bench", 4, 512, usage) : 64;
  const Material cotton = *material_preset("cotton");
  std::printf("grid %d x %d, 1 m, corners pinned, cotton (docs/sim.md), 3 s of hanging\n\n", grid, grid);

  std::printf("cost and shape at 60 Hz (medians):\n");
  const Run pbd = hang(options(SolverKind::Pbd, grid, 1.0F / 60.0F, 2, cotton), 3.0);
  const Run provot = hang(options(SolverKind::Provot, grid, 1.0F / 60.0F, 32, cotton), 3.0);
  std::printf("  pbd    (2 sub-steps):  %7.3f ms/step  strain %.4f  sag %.4f m  fastest %.3f m/s  %s\n", pbd.step_ms,
              static_cast<double>(pbd.strain), static_cast<double>(pbd.sag_m), static_cast<double>(pbd.fastest), verdict(pbd));
  std::printf("  provot (32 sub-steps): %7.3f ms/step  strain %.4f  sag %.4f m  fastest %.3f m/s  %s  (%.1fx pbd's cost)\n",
              provot.step_ms, static_cast<double>(provot.strain), static_cast<double>(provot.sag_m),
              static_cast<double>(provot.fastest), verdict(provot), provot.step_ms / pbd.step_ms);

  std::printf("\nprovot over the sub-step count at dt = 1/60 s (the springs are capped to the explicit limit):\n");
  for (const int n : {1, 4, 8, 16, 32, 64}) {
    const SessionOptions o = options(SolverKind::Provot, grid, 1.0F / 60.0F, n, cotton);
    ProvotParams p = o.provot;
    p.material = cotton;
    ProvotSolver probe{p};
    ClothConfig cc = o.cloth;
    Cloth cloth{cc};
    probe.step(cloth);
    const Run r = hang(o, 3.0);
    std::printf("  %2d sub-steps (h = %.5f s): stiffness kept %.4f  strain %.4f  sag %.4f m  %7.3f ms/step  %s\n", n,
                1.0 / 60.0 / n, static_cast<double>(probe.stiffness_scale()), static_cast<double>(r.strain),
                static_cast<double>(r.sag_m), r.step_ms, verdict(r));
  }
  const float m = cotton.mass_per_area_kg_m2 / static_cast<float>((grid - 1) * (grid - 1));
  const SpringStiffness k = spring_stiffness(cotton, 1.0F / static_cast<float>(grid - 1), 1.0F / static_cast<float>(grid - 1));
  std::printf("  uncapped cotton springs would need h < sqrt(2 m / sum k) = %.2e s (%.0f sub-steps at 60 Hz)\n",
              std::sqrt(2.0 * m / (4.0 * (k.structural + k.shear + k.bend))),
              1.0 / 60.0 / std::sqrt(2.0 * m / (4.0 * (k.structural + k.shear + k.bend))));

  std::printf("\npbd over the time step, 1 sub-step:\n");
  for (const float dt : {1.0F / 120.0F, 1.0F / 60.0F, 1.0F / 30.0F, 1.0F / 15.0F}) {
    const Run r = hang(options(SolverKind::Pbd, grid, dt, 1, cotton), 3.0);
    std::printf("  dt = 1/%-3.0f s: strain %.4f  sag %.4f m  fastest %.3f m/s  %s\n", 1.0 / dt, static_cast<double>(r.strain),
                static_cast<double>(r.sag_m), static_cast<double>(r.fastest), verdict(r));
  }

  std::printf("\none cut (razor, horizontal through the middle at 0.5 m/s, top edge pinned):\n");
  for (const SolverKind kind : {SolverKind::Pbd, SolverKind::Provot}) {
    SessionOptions o = options(kind, grid, 1.0F / 60.0F, kind == SolverKind::Pbd ? 2 : 32, cotton);
    o.cloth.pin = PinMode::TopEdge;
    o.stroke.blade = Blade::Razor;
    Session session{o};
    for (int s = 0; s < 60; ++s) session.step();
    float worst = 0.0F;
    for (int s = 0; s <= 168; ++s) {
      const float x = -0.7F + 1.4F * static_cast<float>(s) / 168.0F;
      session.on_hand({1, 1.0 + s / 60.0, {x, 0.0F, 0.02F}, true, s < 168});
      session.step();
      worst = std::max(worst, session.cloth().max_structural_strain());
    }
    for (int s = 0; s < 60; ++s) session.step();
    const auto reports = session.take_cut_reports();
    const CutReport r = reports.empty() ? CutReport{} : reports.back();
    std::printf("  %-6s: cut %.3f m, %zu pieces (%zu falling), blade drag %.4f m, strain during the cut %.4f\n",
                std::string{to_string(kind)}.c_str(), static_cast<double>(r.stroke.cut_length_m), r.pieces, r.fallen_pieces,
                static_cast<double>(r.drag_m), static_cast<double>(worst));
  }
  return 0;
}
