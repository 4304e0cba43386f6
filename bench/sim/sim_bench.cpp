// sim_bench: time of one 1/60 s step of the tachi cloth against Bullet 3's soft body on the same grid,
// in the same process, pinned the same way (the two top corners), from the same start (hanging flat
// in the z = 0 plane). Prints medians, the speed ratio and both max structural stretches.
// Bullet: btSoftBodyHelpers::CreatePatch with diagonals + links two apart (Provot's spring set),
// piterations = 4 (with 1 it explodes for N >= 32 and disables the body), deactivation off so that
// it is never timed asleep; its activation state is checked and printed.
//
// Usage: sim_bench [--grids 32,64,128,256] [--warmup 60] [--steps 120] [--variants]
//                  [--threads 1,2 [--no-bullet]]
//   --threads: tachi's step on each of these thread counts (SolverParams::threads), each against the first;
//     --no-bullet leaves Bullet out (it takes seconds a step at 512 x 512).
//   --xpbd N: only the second anchor, a textbook small-steps XPBD cloth (run_xpbd) at tachi's maximum strain, N x N.
//   --variants: also print the solver-design table of docs/sim.md (sub-steps x passes, attachments).
//   --bullet-bending-helper: give Bullet generateBendingConstraints(2) instead of the same bend links as
//     ours (more links, slower; needs nodes^2 ints while building: up to 128^2 only).
#include "../bench_args.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/solver.hpp"

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
constexpr btScalar kDt = btScalar(1) / btScalar(60);
using tachi::sim::Cloth;
using tachi::sim::ClothConfig;
using tachi::sim::PinMode;
using tachi::sim::Solver;
using tachi::sim::SolverParams;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Run {
  double step_ms = 0.0;      ///< median wall time of one 1/60 s step
  double max_strain = 0.0;   ///< at the end of the run, over structural springs
  double peak_strain = 0.0;  ///< largest seen after any timed step
  int state = -1;            ///< Bullet's activation state at the end (-1: not Bullet)
};

Cloth make_cloth(int n) {
  ClothConfig c;
  c.columns = n;
  c.rows = n;
  c.pin = PinMode::Corners;
  return Cloth{c};
}

Run run_tachi(int n, int warmup, int steps, const SolverParams& params, bool horizontal = false) {
  Cloth cloth = make_cloth(n);
  if (horizontal) {
    for (auto& p : cloth.position) p = Eigen::Vector3f{p.x(), 0.5F, 0.5F - p.y()};
  }
  Solver solver{params};
  Run r;
  for (int s = 0; s < warmup; ++s) solver.step(cloth);
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s) {
    const auto t0 = Clock::now();
    solver.step(cloth);
    ms.push_back(ms_since(t0));
    r.peak_strain = std::max(r.peak_strain, static_cast<double>(cloth.max_structural_strain()));
  }
  r.step_ms = median(ms);
  r.max_strain = cloth.max_structural_strain();
  return r;
}

/// Bullet soft-body world with one patch, owned together.
struct BulletCloth {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver constraint_solver;
  btDefaultSoftBodySolver soft_solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &constraint_solver, &configuration, &soft_solver};
  btSoftBody* patch = nullptr;
  float spacing = 0.0F;

  /// bending_helper: Bullet's generateBendingConstraints(2) instead of Provot's bend links. It links every
  /// pair of nodes two links apart (diagonals included): more links, and a nodes^2 matrix while building.
  BulletCloth(int n, bool bending_helper) {
    world.setGravity(btVector3(0, -9.81F, 0));
    btSoftBodyWorldInfo& info = world.getWorldInfo();
    info.m_gravity.setValue(0, -9.81F, 0);
    info.m_sparsesdf.Initialize();
    // corner00 = top-left, corner10 = top-right: fixeds 1 + 2 pins the two top corners, as --pin corners.
    patch = btSoftBodyHelpers::CreatePatch(info, btVector3(-0.5F, 0.5F, 0), btVector3(0.5F, 0.5F, 0),
                                           btVector3(-0.5F, -0.5F, 0), btVector3(0.5F, -0.5F, 0), n, n, 1 + 2,
                                           /*gendiags=*/true);
    // Bend links two nodes apart along rows and columns (Provot's bend springs). Added by hand:
    // generateBendingConstraints builds a nodes^2 adjacency matrix (1 GB at 128^2, 17 GB at 256^2).
    if (bending_helper) {
      patch->generateBendingConstraints(2, patch->m_materials[0]);
    } else {
      for (int v = 0; v < n; ++v) {
        for (int u = 0; u < n; ++u) {
          if (u + 2 < n) append_bend(v * n + u, v * n + u + 2);
          if (v + 2 < n) append_bend(v * n + u, (v + 2) * n + u);
        }
      }
    }
    patch->m_cfg.piterations = 4;
    patch->setTotalMass(0.2F);
    patch->setActivationState(DISABLE_DEACTIVATION);
    world.addSoftBody(patch);
    spacing = 1.0F / static_cast<float>(n - 1);
  }
  void append_bend(int a, int b) { patch->appendLink(a, b, patch->m_materials[0]); }

  ~BulletCloth() {
    world.removeSoftBody(patch);
    delete patch;
  }
  BulletCloth(const BulletCloth&) = delete;
  BulletCloth& operator=(const BulletCloth&) = delete;

  /// Max over structural links (rest length = grid spacing) of length / rest - 1.
  [[nodiscard]] double max_strain() const {
    double worst = 0.0;
    for (int i = 0; i < patch->m_links.size(); ++i) {
      const btSoftBody::Link& l = patch->m_links[i];
      if (std::abs(l.m_rl - spacing) > 0.01F * spacing) continue;  // diagonal or bending link
      const double len = (l.m_n[0]->m_x - l.m_n[1]->m_x).length();
      worst = std::max(worst, len / static_cast<double>(l.m_rl) - 1.0);
    }
    return worst;
  }
};

Run run_bullet(int n, int warmup, int steps, bool bending_helper) {
  BulletCloth b{n, bending_helper};
  Run r;
  for (int s = 0; s < warmup; ++s) b.world.stepSimulation(kDt, 1, kDt);
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s) {
    const auto t0 = Clock::now();
    b.world.stepSimulation(kDt, 1, kDt);
    ms.push_back(ms_since(t0));
    r.peak_strain = std::max(r.peak_strain, b.max_strain());
  }
  r.step_ms = median(ms);
  r.max_strain = b.max_strain();
  r.state = b.patch->getActivationState();
  return r;
}

/// A body Bullet disabled (5) or put to sleep (2) costs ~0 per step: such a time is not a measurement.
std::string note_of(int state) {
  return state == DISABLE_SIMULATION ? "DISABLED by Bullet: time invalid"
         : state == ISLAND_SLEEPING  ? "asleep: time invalid"
                                     : "active (state " + std::to_string(state) + ")";
}

/// Runs `measure` in a fresh child process. In one long process the 256^2 step measured 5.0 ms alone,
/// 6.4 ms after a 128^2 run and 9.1 ms after the 32..128 runs (ours and Bullet's), and Bullet's 128^2
/// step varied 5.8-10 ms with what ran before: the heap earlier runs leave behind, not the solvers.
/// tachi-sim builds one cloth per process, so each measurement gets a fresh process. Falls back to
/// running in-process if fork fails. The note string does not cross the pipe: `note_of` rebuilds it.
template <typename Measure>
Run run_fresh(const Measure& measure) {
  int fds[2];
  if (pipe(fds) != 0) return measure();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return measure();
  }
  if (pid == 0) {
    close(fds[0]);
    const Run r = measure();
    const double out[4] = {r.step_ms, r.max_strain, r.peak_strain, static_cast<double>(r.state)};
    const bool ok = write(fds[1], out, sizeof out) == static_cast<ssize_t>(sizeof out);
    _exit(ok ? 0 : 1);
  }
  close(fds[1]);
  double in[4] = {0.0, 0.0, 0.0, 0.0};
  const bool ok = read(fds[0], in, sizeof in) == static_cast<ssize_t>(sizeof in);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!ok) return measure();
  Run r;
  r.step_ms = in[0];
  r.max_strain = in[1];
  r.peak_strain = in[2];
  r.state = static_cast<int>(in[3]);
  return r;
}

/// A comma-separated list of whole numbers in [min, max]; a bad item is an error naming `flag` (exit 2),
/// not dropped or read as its leading digits.
std::vector<int> parse_list(const std::string& text, const char* flag, int min, int max, const char* usage) {
  std::vector<int> out;
  std::stringstream ss{text};
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(tachi::bench::int_argument(item.c_str(), flag, min, max, usage));
  return out;
}

/// The second anchor: a textbook XPBD cloth with small steps (Macklin et al. 2019, "Small steps in
/// physics simulation": n sub-steps of one Gauss-Seidel iteration each, lambda starting at 0 in each, so each
/// projection is eq. 18 of Macklin et al. 2016 with compliance alpha / h^2). The same springs (structural hard,
/// shear and bend with tachi's compliances), masses, pins and air damping as tachi's step; no tethers, no
/// strain limit, no batching: one spring after another in the cloth's order, plain scalar code.
Run run_xpbd(int n, int substeps, int warmup, int steps, bool horizontal) {
  Cloth cloth = make_cloth(n);
  if (horizontal) {
    for (auto& p : cloth.position) p = Eigen::Vector3f{p.x(), 0.5F, 0.5F - p.y()};
  }
  // In double precision: at small sub-steps a step's motion, g h^2 (6.7e-7 m at 64 sub-steps of 1/60 s), is a
  // few float ulps of a position near 1 m (6e-8 m), and v = (x - x_old) / h turns their rounding into a random
  // walk of the velocities: in float the 64 x 64 cloth went non-finite at 64 sub-steps, in double it rests at
  // 4-9 % strain (measured 2026-12-04).
  const SolverParams defaults;
  const double h = static_cast<double>(kDt) / substeps;
  std::array<double, 3> alpha{};  // by SpringKind: structural, shear, bend
  alpha[static_cast<std::size_t>(tachi::sim::SpringKind::Structural)] = defaults.structural_compliance / (h * h);
  alpha[static_cast<std::size_t>(tachi::sim::SpringKind::Shear)] = defaults.shear_compliance / (h * h);
  alpha[static_cast<std::size_t>(tachi::sim::SpringKind::Bend)] = defaults.bend_compliance / (h * h);
  const std::size_t count = cloth.particle_count();
  std::vector<Eigen::Vector3d> x(count), v(count, Eigen::Vector3d::Zero()), old(count);
  for (std::size_t i = 0; i < count; ++i) x[i] = cloth.position[i].cast<double>();
  const Eigen::Vector3d gravity = defaults.gravity.cast<double>();
  const auto step = [&] {
    for (int sub = 0; sub < substeps; ++sub) {
      const double keep = std::max(0.0, 1.0 - defaults.damping * h);
      for (std::size_t i = 0; i < count; ++i) {
        old[i] = x[i];
        if (cloth.inverse_mass[i] == 0.0F) continue;
        v[i] = v[i] * keep + gravity * h;
        x[i] += v[i] * h;
      }
      for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
        if (cloth.alive[k] == 0) continue;
        Eigen::Vector3d& a = x[cloth.spring_a[k]];
        Eigen::Vector3d& b = x[cloth.spring_b[k]];
        const double wa = cloth.inverse_mass[cloth.spring_a[k]];
        const double wb = cloth.inverse_mass[cloth.spring_b[k]];
        const Eigen::Vector3d d = b - a;
        const double len = d.norm();
        if (wa + wb == 0.0 || len < 1e-12) continue;
        const double c = (len - cloth.rest_length[k]) / (len * (wa + wb + alpha[static_cast<std::size_t>(cloth.kind[k])]));
        a += (wa * c) * d;
        b -= (wb * c) * d;
      }
      for (std::size_t i = 0; i < count; ++i) v[i] = (x[i] - old[i]) / h;
    }
    for (std::size_t i = 0; i < count; ++i) cloth.position[i] = x[i].cast<float>();  // for the strain below
  };
  // A cloth that came apart (non-finite positions) has no finite strain: +inf, not what max() makes of NaN.
  const auto strain = [&] {
    const bool finite = std::all_of(cloth.position.begin(), cloth.position.end(),
                                    [](const Eigen::Vector3f& p) { return p.allFinite(); });
    return finite ? static_cast<double>(cloth.max_structural_strain()) : std::numeric_limits<double>::infinity();
  };
  Run r;
  for (int s = 0; s < warmup; ++s) step();
  std::vector<double> ms;
  for (int s = 0; s < steps; ++s) {
    const auto t0 = Clock::now();
    step();
    ms.push_back(ms_since(t0));
    r.peak_strain = std::max(r.peak_strain, strain());
  }
  r.step_ms = median(ms);
  r.max_strain = strain();
  return r;
}

/// tachi's default step against the textbook XPBD cloth at the same maximum strain, 128 x 128 (or `n`), on the
/// hanging cloth (strain at the end of the run) and the swinging one (horizontal start, peak over the run):
/// XPBD's sub-steps double until its strain is no more than tachi's.
void print_xpbd_anchor(int n, int warmup, int steps) {
  std::printf("\nTextbook XPBD, small steps (Macklin et al. 2019), %dx%d, same springs, one iteration per sub-step:\n",
              n, n);
  std::printf("%9s %10s %10s %12s %10s %10s\n", "cloth", "solver", "sub-steps", "ms a step", "strain", "vs tachi");
  for (const bool swinging : {false, true}) {
    const int w = swinging ? 0 : warmup;
    const SolverParams defaults;
    const Run t = run_fresh([&] { return run_tachi(n, w, steps, defaults, swinging); });
    const double tachi_strain = swinging ? t.peak_strain : t.max_strain;
    const char* cloth = swinging ? "swinging" : "hanging";
    std::printf("%9s %10s %10d %12.3f %9.1f%% %10s\n", cloth, "tachi", defaults.substeps, t.step_ms,
                100.0 * tachi_strain, "1.00x");
    constexpr int kMostSubsteps = 1024;
    for (int substeps = 8; substeps <= kMostSubsteps; substeps *= 2) {
      const Run x = run_fresh([&] { return run_xpbd(n, substeps, w, steps, swinging); });
      const double strain = swinging ? x.peak_strain : x.max_strain;
      std::printf("%9s %10s %10d %12.3f %9.1f%% %9.1fx\n", cloth, "xpbd", substeps, x.step_ms, 100.0 * strain,
                  x.step_ms / t.step_ms);
      std::fflush(stdout);
      if (strain <= tachi_strain) break;
    }
  }
}

void print_variants(int warmup) {
  struct Variant {
    const char* name;
    int substeps;
    int iterations;
    bool attachments;
    int strain_passes;
  };
  const Variant variants[] = {
      {"1 sub-step x 4 passes, attachments", 1, 4, true, 4},
      {"1 sub-step x 1 pass, attachments", 1, 1, true, 4},
      {"2 sub-steps x 1 pass, no attachments", 2, 1, false, 4},
      {"2 sub-steps x 1 pass, attachments, 1 limit sweep", 2, 1, true, 1},
      {"2 sub-steps x 1 pass, attachments (default)", 2, 1, true, 4},
      {"2 sub-steps x 2 passes, attachments", 2, 2, true, 4},
      {"3 sub-steps x 1 pass, attachments", 3, 1, true, 4},
      {"4 sub-steps x 1 pass, attachments", 4, 1, true, 4},
  };
  std::printf("\nSolver variants, 128x128, corners pinned (hanging: warm-up %d + 120 steps; swing: released\n"
              "from horizontal, 300 steps):\n",
              warmup);
  std::printf("%-52s %10s %10s %12s %12s\n", "variant", "ms/step", "strain", "swing ms", "swing peak");
  for (const Variant& v : variants) {
    SolverParams p;
    p.substeps = v.substeps;
    p.iterations = v.iterations;
    p.long_range_attachments = v.attachments;
    p.strain_limit_passes = v.strain_passes;
    const Run hang = run_tachi(128, warmup, 120, p);
    const Run swing = run_tachi(128, 0, 300, p, /*horizontal=*/true);
    std::printf("%-52s %10.3f %9.1f%% %12.3f %11.1f%%\n", v.name, hang.step_ms, 100.0 * hang.max_strain,
                swing.step_ms, 100.0 * swing.peak_strain);
  }
}

/// Lower bound on an implicit step (Baraff & Witkin 1998, eq. 18): one solve of (M + h^2 K) dv = b with
/// Eigen's conjugate gradient, where K is the isotropic spring Laplacian (stiffness k on every spring);
/// the true Jacobian has 3x3 blocks that change every step (assembly not timed here).
void print_implicit_lower_bound(int n) {
  Cloth cloth = make_cloth(n);
  const auto np = static_cast<Eigen::Index>(cloth.particle_count());
  const float h = 1.0F / 60.0F;
  const float k = 1000.0F;  // N/m: a stiff cloth (stretch under its own weight ~1e-3)
  std::vector<Eigen::Triplet<float>> t;
  for (Eigen::Index i = 0; i < np; ++i) {
    for (int c = 0; c < 3; ++c) t.emplace_back(3 * i + c, 3 * i + c, cloth.mass[static_cast<std::size_t>(i)]);
  }
  for (std::size_t s = 0; s < cloth.spring_count(); ++s) {
    const auto a = static_cast<Eigen::Index>(cloth.spring_a[s]), b = static_cast<Eigen::Index>(cloth.spring_b[s]);
    for (int c = 0; c < 3; ++c) {
      t.emplace_back(3 * a + c, 3 * a + c, h * h * k);
      t.emplace_back(3 * b + c, 3 * b + c, h * h * k);
      t.emplace_back(3 * a + c, 3 * b + c, -h * h * k);
      t.emplace_back(3 * b + c, 3 * a + c, -h * h * k);
    }
  }
  Eigen::SparseMatrix<float> m(3 * np, 3 * np);
  m.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXf rhs = Eigen::VectorXf::Zero(3 * np);
  for (Eigen::Index i = 0; i < np; ++i) rhs[3 * i + 1] = -9.81F * h * cloth.mass[static_cast<std::size_t>(i)];
  Eigen::ConjugateGradient<Eigen::SparseMatrix<float>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-3F);
  const auto t0 = Clock::now();
  cg.compute(m);
  const Eigen::VectorXf dv = cg.solve(rhs);
  const double ms = ms_since(t0);
  std::printf("\nImplicit Euler lower bound, %dx%d: one CG solve of %ld unknowns, %ld iterations, %.2f ms\n", n, n,
              static_cast<long>(3 * np), static_cast<long>(cg.iterations()), ms);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> grids{32, 64, 128, 256};
  int warmup = 60;
  int steps = 120;
  bool variants = false;
  bool bending_helper = false;
  std::vector<int> thread_counts;
  bool bullet = true;
  int xpbd = 0;
  const char* usage = "usage: sim_bench [--grids 32,64,128,256] [--warmup 60] [--steps 120] [--variants]\n"
                      "                 [--bullet-bending-helper] [--threads 1,2 [--no-bullet]] [--xpbd 128]\n";
  tachi::bench::exit_on_help(argc, argv, usage);
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--grids" && has_value) {
      grids = parse_list(argv[++i], "sim_bench --grids", 2, 1024, usage);
    } else if (arg == "--warmup" && has_value) {
      warmup = tachi::bench::int_argument(argv[++i], "sim_bench --warmup", 0, 1000000, usage);
    } else if (arg == "--steps" && has_value) {
      steps = tachi::bench::int_argument(argv[++i], "sim_bench --steps", 1, 1000000, usage);
    } else if (arg == "--variants") {
      variants = true;
    } else if (arg == "--bullet-bending-helper") {
      bending_helper = true;
    } else if (arg == "--threads" && has_value) {
      thread_counts = parse_list(argv[++i], "sim_bench --threads", 1, 64, usage);
    } else if (arg == "--no-bullet") {
      bullet = false;
    } else if (arg == "--xpbd" && has_value) {
      xpbd = tachi::bench::int_argument(argv[++i], "sim_bench --xpbd", 2, 1024, usage);
    } else {
      std::fprintf(stderr, "sim_bench: unknown or incomplete argument '%s'\n%s", arg.c_str(), usage);
      return 2;
    }
  }
  if (grids.empty()) {
    std::fprintf(stderr, "sim_bench: --grids needs sizes in 2..1024\n");
    return 2;
  }

  std::printf("sim_bench: one 1/60 s step, corners pinned, hanging start; warm-up %d steps, median of %d\n", warmup,
              steps);
  if (xpbd > 0) {
    print_xpbd_anchor(xpbd, warmup, steps);
    return 0;
  }
  if (!thread_counts.empty()) {
    // Each count in its own process, one after another for each grid: the first is the reference.
    std::printf("%6s %8s %12s %12s %12s %10s\n", "grid", "threads", "tachi ms", "end strain", "peak strain",
                "speed-up");
    for (const int n : grids) {
      double reference = 0.0;
      for (const int t : thread_counts) {
        SolverParams params;
        params.threads = t;
        const Run r = run_fresh([&] { return run_tachi(n, warmup, steps, params); });
        if (reference == 0.0) reference = r.step_ms;
        std::printf("%6s %8d %12.3f %11.1f%% %11.1f%% %9.2fx\n", (std::to_string(n) + "^2").c_str(), t, r.step_ms,
                    100.0 * r.max_strain, 100.0 * r.peak_strain, reference / r.step_ms);
        std::fflush(stdout);
      }
    }
    if (!bullet) return 0;
  }
  std::printf("Bullet springs: %s\n", bending_helper ? "CreatePatch diagonals + generateBendingConstraints(2)"
                                                     : "CreatePatch diagonals + bend links two apart (same set as tachi)");
  std::printf("%6s %12s %12s %12s %12s %10s  %s\n", "grid", "tachi ms", "tachi strain", "bullet ms", "bullet strain",
              "speed-up", "bullet body");
  const SolverParams defaults;
  for (const int n : grids) {
    const Run t = run_fresh([&] { return run_tachi(n, warmup, steps, defaults); });
    const Run b = run_fresh([&] { return run_bullet(n, warmup, steps, bending_helper); });
    std::printf("%6s %12.3f %11.1f%% %12.3f %12.1f%% %9.1fx  %s\n", (std::to_string(n) + "^2").c_str(), t.step_ms,
                100.0 * t.max_strain, b.step_ms, 100.0 * b.max_strain, b.step_ms / t.step_ms, note_of(b.state).c_str());
    std::fflush(stdout);
  }
  if (variants) {
    print_variants(warmup);
    print_implicit_lower_bound(128);
  }
  return 0;
}
