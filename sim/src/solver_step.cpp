// The time step (Solver::step) and its sub-steps: position-based dynamics (Mueller et al. 2007) with XPBD
// soft springs (Macklin et al. 2016), long-range attachments (Kim, Chentanez, Mueller 2012) and Provot's
// deformation constraint (Provot 1995, sec. 4); the pipeline of one sub-step is in solver.hpp. On several
// threads steps 1-4 of a sub-step run in one OpenMP region (front_in_bands). Also the parameters' check.
// The caches a step reads are kept by solver_caches.cpp; each step's own parts live in spring_batches.cpp
// (steps 3-4), tethers.cpp (step 2), strain_limit.cpp (step 5).
#include "tachi/sim/solver.hpp"

#include "constraint_kernels.hpp"
#include "solver_common.hpp"

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

namespace tachi::sim {

using solver_detail::for_chunks;
using solver_detail::Vec4;

std::optional<const char*> validate(const SolverParams& p) {
  if (!(p.dt > 0.0F) || !(p.dt <= 1.0F)) return "dt must be in (0, 1] s";
  if (p.substeps < 1 || p.substeps > 64) return "substeps must be in [1, 64]";
  if (p.iterations < 1 || p.iterations > 200) return "iterations must be in [1, 200]";
  if (!p.gravity.allFinite()) return "gravity must be finite";
  if (!(p.damping >= 0.0F) || !std::isfinite(p.damping)) return "damping must be >= 0";
  if (!(p.shear_compliance >= 0.0F) || !(p.bend_compliance >= 0.0F) || !(p.structural_compliance >= 0.0F))
    return "compliance must be >= 0";
  if (!(p.max_strain > 0.0F) || !(p.max_strain < 10.0F)) return "max_strain must be in (0, 10)";
  if (p.strain_limit_passes < 1 || p.strain_limit_passes > 100) return "strain_limit_passes must be in [1, 100]";
  if (p.repair_per_step < 1) return "repair_per_step must be at least 1";
  if (p.repair_share < 0) return "repair_share must be >= 0";
  if (p.cut_work_per_step < 0) return "cut_work_per_step must be >= 0";
  if (p.threads < 1 || p.threads > 64) return "threads must be in [1, 64]";
  return std::nullopt;
}

int default_solver_threads() {
  const unsigned cores = std::thread::hardware_concurrency();
  return cores <= 1 ? 1 : static_cast<int>(std::min(cores - 1, 64U));
}

Solver::Solver(SolverParams params) : params_(std::move(params)) {}

Solver::Solver(const Cloth& cloth, SolverParams params) : Solver(std::move(params)) { prepare(cloth); }

void Solver::prepare(const Cloth& cloth) {
  refresh_caches(cloth);
  if (tether_order_stale_) order_tethers();
}

void Solver::step(Cloth& cloth, const Colliders& colliders) {
  refresh_caches(cloth);
  // A cut's tether work that its own step could not finish (SolverParams::cut_work_per_step) goes on over
  // the steps after it, in even slices: what is left over the steps left (kMaxCutWorkSteps), at least
  // cut_work_per_step. The repairs wait for it: during the pass that opens the orphans' subtrees they would
  // settle particles from distances it has yet to open, and during the labelling they would seed the
  // particles of the piece it is about to release (a 128 x 128 cloth's lower half: 1 ms a step). They
  // resume on the step after it ends, which has paid for the release.
  const bool cut_work = cut_work_pending();
  if (cut_work) {
    ++cut_work_steps_;
    if (cut_work_fresh_) {
      cut_work_fresh_ = false;  // the step of the cut: its update did this step's slice
    } else {
      const auto steps_left = static_cast<std::size_t>(std::max(1, kMaxCutWorkSteps - cut_work_steps_));
      const bool overdue = cut_work_steps_ >= kMaxCutWorkSteps;
      const std::size_t even = (cut_work_left(cloth) + steps_left - 1) / steps_left;
      advance_cut_work(cloth, overdue ? static_cast<std::size_t>(-1)
                                      : std::max(even, static_cast<std::size_t>(params_.cut_work_per_step)));
    }
  } else {
    continue_repairs(cloth);
  }
  engage_tethers();
  if (tether_order_stale_) order_tethers();
  const std::size_t n = cloth.particle_count();
  // Work on (x, y, z, w) quadruples: one aligned 16-byte load brings a position and its inverse mass.
  // Element 0 is the padding lanes' particle (never moves: inverse mass 0); particle i is element i + 1.
  work_.resize(n + 1);
  work_[0] = Eigen::Vector4f::Zero();
  old_work_.resize(n + 1);
  for_chunks(n, params_.threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) work_[i + 1] << cloth.position[i], cloth.inverse_mass[i];
  });
  const float h = params_.dt / static_cast<float>(params_.substeps);
  for (int s = 0; s < params_.substeps; ++s) substep(cloth, colliders, h, s == 0, s + 1 == params_.substeps);
  loose_swept_ = !loose_springs_.empty();  // the next refresh_caches batches them (fold_loose_springs)
  if (params_.threads > 1 && banded()) return;  // the last sub-step wrote the positions back (substep)
  for_chunks(n, params_.threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) cloth.position[i] = work_[i + 1].head<3>();
  });
}

using solver_detail::sweep_near_rest;
using solver_detail::sweep_tethers;

template <typename Predict>
bool Solver::front_in_bands(Vec4* x, std::size_t n, const Predict& predict, bool soft, float shear_alpha,
                            float bend_alpha, float structural_alpha, float limit) {
  Vec4* const padded = x - 1;
  const int threads = params_.threads;
  const bool ordered = !tether_order_.empty();
  // Where each pin group's block of unbent tethers runs in the order they apply (sweep_all_tethers).
  constexpr std::size_t kMaxBlocks = 8;
  std::array<std::size_t, kMaxBlocks + 1> block{};
  const std::size_t blocks = std::min(tether_block_end_.size(), kMaxBlocks);
  for (std::size_t b = 0; b < blocks; ++b) {
    block[b + 1] = ordered ? static_cast<std::size_t>(
                                 std::lower_bound(tether_order_.begin(),
                                                  tether_order_.begin() + static_cast<std::ptrdiff_t>(unbent_tethers_),
                                                  tether_block_end_[b]) -
                                 tether_order_.begin())
                           : tether_block_end_[b];
  }
  const std::size_t count = ordered ? tether_order_.size() : attachments_.size();
  const std::size_t rest = block[blocks];
  const int bands = static_cast<int>(bands_[0].size()) - 1;
  // With no cut's springs to sweep after the bands (each went to the band of its rows: place_cut_quads),
  // the strain limit's first reading (mark_over_limit) joins the region: one wait for the other thread fewer
  // per sub-step.
  bool mark = limit > 0.0F;
  for (std::size_t f = 0; f < 3; ++f) mark = mark && unbanded_runs_[f].empty();
  for (const auto& loose : loose_bands_) mark = mark && (loose.empty() || loose.back().empty());
  const auto words = static_cast<std::ptrdiff_t>(limit_dirty_.size());
  const auto run = [&](const auto& at) {
    // The first place in [from, to) of a block (sorted by particle) whose tether holds `particle` or a later one.
    const auto first_from = [&](std::size_t from, std::size_t to, std::size_t particle) {
      while (from < to) {
        const std::size_t mid = from + (to - from) / 2;
        if (at(mid).particle < particle) {
          from = mid + 1;
        } else {
          to = mid;
        }
      }
      return from;
    };
    const auto tethers = [&](std::size_t from, std::size_t to) {
      sweep_tethers(x, to - from, [&](std::size_t k) -> const Attachment& { return at(from + k); });
    };
#pragma omp parallel num_threads(threads)
    {
#pragma omp for schedule(static)
      for (int c = 0; c < threads; ++c) {
        const std::size_t begin = n * static_cast<std::size_t>(c) / static_cast<std::size_t>(threads);
        const std::size_t end = n * static_cast<std::size_t>(c + 1) / static_cast<std::size_t>(threads);
        predict(begin, end);
        for (std::size_t b = 0; b < blocks; ++b) {
          const std::size_t from = first_from(block[b], block[b + 1], begin);
          tethers(from, first_from(from, block[b + 1], end));
        }
      }
      if (rest < count) {
#pragma omp single
        tethers(rest, count);  // added by repairs, or anchored past a bend: in order
      }
      for (int parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(static)
        for (int j = parity; j < bands; j += 2) {
          // Explicit captures: clang 14 refuses a by-reference default capture of the enclosing
          // function's locals in a lambda inside an OpenMP region of a template.
          Vec4* const band_padded = padded;
          const auto band = [this, band_padded, j](std::size_t family, float alpha) {
            sweep_band(band_padded, family, static_cast<std::size_t>(j), alpha);
          };
          if (soft) {
            band(1, shear_alpha);
            band(2, bend_alpha);
          }
          for (int it = 0; it < params_.iterations; ++it) band(0, structural_alpha);
        }
      }
      if (mark) {
#pragma omp for schedule(static)
        for (std::ptrdiff_t w = 0; w < words; ++w) mark_word(x, limit, static_cast<std::size_t>(w));
      }
    }
  };
  if (ordered) {
    run([this](std::size_t k) -> const Attachment& { return attachments_[tether_order_[k]]; });
  } else {
    run([this](std::size_t k) -> const Attachment& { return attachments_[k]; });
  }
  // A cut's springs that fit no band: after the bands, in order, family after family.
  if (soft) {
    sweep_unbanded(padded, 1, shear_alpha);
    sweep_unbanded(padded, 2, bend_alpha);
  }
  for (int it = 0; it < params_.iterations; ++it) sweep_unbanded(padded, 0, structural_alpha);
  return mark;
}

void Solver::substep(Cloth& cloth, const Colliders& colliders, float h, bool first, bool last_substep) {
  const std::size_t n = cloth.particle_count();
  Vec4* const padded = work_.data();
  Vec4* x = padded + 1;  // particle i
  Eigen::Vector3f* v = cloth.velocity.data();
  const int threads = params_.threads;
  const Vec4* old_x = old_work_.data() + 1;
  const float keep = std::max(0.0F, 1.0F - params_.damping * h);
  const Eigen::Vector3f gh = params_.gravity * h;
  const PointCloudCollider* cloud = colliders.point_cloud;
  const bool soft = first || params_.soft_every_substep;
  const float full_h = params_.soft_every_substep ? h : params_.dt;
  const float shear_alpha = params_.shear_compliance / (full_h * full_h);
  const float bend_alpha = params_.bend_compliance / (full_h * full_h);
  const float structural_alpha = params_.structural_compliance / (h * h);
  // 1. Prediction (symplectic Euler on external forces; seed 000's point-cloud repulsion is one of them).
  const auto predict = [&](std::size_t begin, std::size_t end) {
    std::copy(work_.begin() + static_cast<std::ptrdiff_t>(begin + 1),
              work_.begin() + static_cast<std::ptrdiff_t>(end + 1), old_work_.begin() + static_cast<std::ptrdiff_t>(begin + 1));
    for (std::size_t i = begin; i < end; ++i) {
      if (x[i].w() == 0.0F) continue;
      Eigen::Vector3f vel = v[i] * keep + gh;
      if (cloud != nullptr) vel += cloud->repulsion(x[i].head<3>()) * h;
      v[i] = vel;
      x[i].head<3>() += vel * h;
    }
  };
  old_work_[0] = work_[0];

  // Step 5's limit, and its bits (a full pass on several threads reads them first: mark_over_limit).
  const float limit = 1.0F + params_.max_strain;
  const std::size_t places = strain_limit_.size();
  limit_dirty_.assign((places + 63) / 64, 0);
  bool premarked = false;
  // 6. Collisions by projection with friction (collide_with_friction), then velocities from the positions
  // actually reached.
  const bool any_collider = !colliders.spheres.empty() || !colliders.boxes.empty() || colliders.ground.has_value() ||
                            cloud != nullptr;
  const float inv_h = 1.0F / h;
  const auto finish = [&](std::size_t begin, std::size_t end) {
    if (any_collider) {
      for (std::size_t i = begin; i < end; ++i) {
        if (x[i].w() == 0.0F) continue;
        Eigen::Vector3f p = x[i].head<3>();
        if (collide_with_friction(p, old_x[i].head<3>(), colliders, h)) x[i].head<3>() = p;
      }
    }
    for (std::size_t i = begin; i < end; ++i) {
      if (x[i].w() == 0.0F) continue;
      v[i] = (x[i].head<3>() - old_x[i].head<3>()) * inv_h;
    }
  };
  const bool fused = threads > 1 && banded();
  if (fused) {
    // Steps 1 to 4 in one parallel region (each wait for the other thread is a chance to lose the core on a
    // shared machine): steps 1 and 2 per range of particles, each thread predicting its particles and then
    // applying their unbent tethers (anchored on pins: sweep_all_tethers), then the springs band by band.
    // Each thread also finishes the previous sub-step's step 6 for its particles first (elementwise, on the
    // same particles it predicts next): one wait fewer per sub-step.
    const auto finish_and_predict = [&](std::size_t begin, std::size_t end) {
      if (!first) finish(begin, end);
      predict(begin, end);
    };
    premarked = front_in_bands(x, n, finish_and_predict, soft, shear_alpha, bend_alpha, structural_alpha,
                               params_.sparse_strain_limit ? limit : 0.0F);
  } else {
    for_chunks(n, threads, predict);

    // 2. Long-range attachments (unilateral): a particle may not be farther from a pin than its rest
    // distance, which removes in one pass the sag that Gauss-Seidel needs O(N^2) passes for.
    // Behind a cut a tether's anchor is a particle, held by its own tether first (tether_order_), and only
    // the particle moves: the anchor stands for the pin the path leads to. Four at a time (sweep_tethers): at
    // 256 x 256 the 261k tethers of four pin groups were 44 % of a step; a third of that went.
    sweep_all_tethers(x);

    // 3. Soft shear and bend springs, one XPBD pass each per sub-step (soft: more passes buy nothing visible).
    if (soft) {
      sweep_springs(padded, 1, shear_alpha);
      sweep_springs(padded, 2, bend_alpha);
    }

    // 4. Structural springs, hard, Gauss-Seidel. Near rest length the square root is replaced by its
    // first-order expansion, |d| ~ (|d|^2 + L^2) / 2L (Jakobsen 2001, "Advanced Character Physics"):
    // the fixed point is still |d| = L, and step 5 below is exact.
    for (int it = 0; it < params_.iterations; ++it) sweep_springs(padded, 0, structural_alpha);
  }

  // 5. Provot's deformation constraint (strain_limit.cpp).
  limit_strain(cloth, x, premarked);

  // 6. (finish, above): in bands on several threads, the next sub-step's region does it, or the last one's
  // here, with the positions written back.
  if (!fused) {
    for_chunks(n, threads, finish);
  } else if (last_substep) {
    for_chunks(n, threads, [&](std::size_t begin, std::size_t end) {
      finish(begin, end);
      for (std::size_t i = begin; i < end; ++i) cloth.position[i] = x[i].head<3>();
    });
  }
}

double mechanical_energy(const Cloth& cloth, const Eigen::Vector3f& gravity, double k_structural) {
  double e = 0.0;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    const double m = cloth.mass[i];
    e += 0.5 * m * static_cast<double>(cloth.velocity[i].squaredNorm());
    e -= m * static_cast<double>(gravity.dot(cloth.position[i]));
  }
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] != SpringKind::Structural) continue;
    const double len = (cloth.position[cloth.spring_a[k]] - cloth.position[cloth.spring_b[k]]).norm();
    const double stretch = len - static_cast<double>(cloth.rest_length[k]);
    e += 0.5 * k_structural * stretch * stretch;
  }
  return e;
}

}  // namespace tachi::sim
