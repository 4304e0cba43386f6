// Time step of the cloth: position-based dynamics with Provot's deformation constraint. Per sub-step:
//   1. predict  v = v (1 - damping h) + h (g + a_repulsion), x* = x + h v       (Mueller et al. 2007, eq. 1-3)
//   2. long-range attachments: |x - x_pin| <= rest distance to the pin          (Kim, Chentanez, Mueller 2012)
//      (behind a cut: to the particle where the shortest path to the pin bends around the cut's tip)
//   3. shear and bend springs as soft constraints, compliance alpha / h^2        (XPBD, Macklin et al. 2016, eq. 18)
//   4. Gauss-Seidel projection of structural springs, C = |xa - xb| - L          (Mueller et al. 2007, sec. 3.3)
//   5. Provot's deformation constraint: structural springs over (1 + max_strain) L pulled back (Provot 1995, sec. 4)
//   6. collisions by projection, with friction; v = (x - x_old) / h
// Deterministic: a fixed iteration order, so the same inputs and thread count give bit-identical results.
// threads > 1 (OpenMP): the springs' sweeps run over bands of rows, the even bands at once, then the odd
// ones (bands share no particle: a two-colouring of a partition, docs/sim.md "Threads"); the tethers, the
// per-particle loops and the strain limit's scan for its first violation are split with the same results
// as one thread; after a cut the pin groups' repairs run at once, a group per thread, each with a share of
// the budget (run_apart). One thread runs the single-threaded code as before.
// Why this and not semi-implicit + Provot or an implicit solver: docs/sim.md (with the figures).
// Where each part is (sim/src): the step and sub-steps solver_step.cpp; the caches solver_caches.cpp; the
// springs' quads and bands spring_batches.cpp (steps 3-4); the tethers tethers.cpp (step 2), their repair after a
// cut tether_repair.cpp and tether_release.cpp; Provot's constraint strain_limit.cpp (step 5).
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/union_find.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace tachi::sim {

struct SolverParams {
  float dt = 1.0F / 60.0F;     ///< seconds per step
  int substeps = 2;            ///< sub-steps per step (each one runs the whole pipeline with dt / substeps)
  int iterations = 1;          ///< structural Gauss-Seidel passes per sub-step
  Eigen::Vector3f gravity{0.0F, -9.81F, 0.0F};
  float damping = 0.5F;            ///< velocity damping, 1/s (air drag)
  float shear_compliance = 0.2F;   ///< XPBD compliance, m/N (inverse spring stiffness)
  float bend_compliance = 2.0F;    ///< XPBD compliance, m/N
  float structural_compliance = 0.0F;  ///< XPBD compliance of the structural springs, m/N (0: hard; materials set 1/k)
  float max_strain = 0.10F;        ///< Provot's critical deformation rate (10%)
  int strain_limit_passes = 6;     ///< full strain-limit sweeps per sub-step at most (stops when clean); local ones follow
  /// After a sub-step's first strain-limit pass, each pass reads only the springs a correction moved an end of
  /// since their last check: the same corrections as reading all of them (false: reads all, for comparison).
  bool sparse_strain_limit = true;
  /// Particles the attachments' repair after a cut settles per step, over all pin groups together: this
  /// many, or the cloth's particles over repair_share if that is more. A cut that re-routes a whole piece is
  /// spread over steps (those particles keep their old tethers meanwhile, except where the cut separated
  /// them from a pin group: Solver::release_cut_off). Until 2026-12-05 it was 2048 per pin group, and the
  /// repair's first step after a 128 x 128 cut settled all four groups' 2673 particles at once: 1.86-1.95x
  /// a plain step (docs/benchmarks.md, "The worst of the steps after a cut, traced").
  int repair_per_step = 1024;
  /// The share of the particles the repair may settle in a step (1 / repair_share; 0: repair_per_step
  /// alone). A settle costs ~300 ns, a step ~55 ns a particle, so a sixteenth costs about a third of a step
  /// at any size, and a large cloth's repair takes as many steps as a small one's.
  int repair_share = 16;
  /// How much of a cut's tether work is done in the cut's own step, in visits (particles opened, 16 entries of a
  /// settle order passed, particles and springs labelled): opening the particles whose shortest paths the cut
  /// broke (a pass over each pin group's settle order) and labelling what it cut off (floods, then union-find
  /// over the springs). The rest goes on over the steps after it in even slices of at least this much, at most
  /// Solver::kMaxCutWorkSteps steps: meanwhile the piece keeps its old tethers and the repairs wait; it is
  /// released in one pass. Cuts that come meanwhile join the work. 1 (the default since 2026-12-05): nearly
  /// all of it spread; the step after a 128 x 128 cut costs 1.2-1.4x a plain one against 3.0-3.7x with 0 (all
  /// of it in the step of the cut), and a long stroke's flap keeps its old tethers until the work ends (peak
  /// strain 8-10 % against 65-992 %). The price: a cut-off piece falls up to kMaxCutWorkSteps steps after it
  /// separates, and the slit behind a long stroke stays shut until then (docs/sim.md "Caches").
  int cut_work_per_step = 1;
  bool long_range_attachments = true;
  bool soft_every_substep = true;  ///< shear/bend in every sub-step (false: cheaper, but never fully at rest)
  /// Threads of the sweeps (OpenMP). The positions are a function of this number, not of how many threads the
  /// system actually grants: 1 gives the single-threaded results bit for bit; > 1 sweeps the springs in
  /// 2 x threads bands of rows (even bands together, then odd) and repairs the pin groups' tethers after a
  /// cut at once, each with an even share of the budget: the same for every run with that number.
  int threads = 1;
};

/// Threads a process uses by default: one core left for the other nodes that share the machine (at least 1).
[[nodiscard]] int default_solver_threads();

/// Returns a message naming the bad field, or nothing.
[[nodiscard]] std::optional<const char*> validate(const SolverParams& params);

/// Steps a Cloth. Keeps caches derived from the cloth's topology (spring batches, strain-limit order,
/// long-range attachments). A full build happens at construction with a cloth, else on the first step, and when the set of fixed particles
/// (pinned, or held by the hand: inverse mass 0) changes; a cut is picked up INCREMENTALLY from
/// cloth.spring_edits: the lanes of the springs it changed are blanked, its new springs are batched at
/// the end of their family, and only the attachments whose shortest path crossed the cut are searched
/// again (decremental Dijkstra), inside the next steps within a budget (repair_per_step), their old tethers
/// kept until then unless the cut separated them from the pins. Details and figures: docs/sim.md
/// ("Caches"), docs/benchmarks.md ("Exact cuts").
class Solver {
 public:
  explicit Solver(SolverParams params = {});
  /// Builds the caches for `cloth` now, what the first step would otherwise do (at 256 x 256 the first step
  /// took 190-440 ms, 15-35 times an ordinary one): the first step is then an ordinary one. Construct it after
  /// the cloth's room for cuts is reserved (StrokeCutter, Cloth::reserve): the build sizes its arrays to it.
  Solver(const Cloth& cloth, SolverParams params);
  /// What that constructor does, for a solver made before the cloth's room for cuts was reserved (a Session
  /// builds its cutter after its solver): builds the caches for `cloth` now.
  void prepare(const Cloth& cloth);

  /// Advances the cloth by params().dt.
  void step(Cloth& cloth, const Colliders& colliders = {});
  /// Picks up the cloth's topology changes now (step() does it first anyway): for timing the update apart.
  /// The attachments' repair after a cut is not part of it: each step goes on with it within a budget.
  void update_topology(const Cloth& cloth) { refresh_caches(cloth); }

  [[nodiscard]] const SolverParams& params() const { return params_; }
  /// Whether the springs are swept in bands of rows on several threads (threads > 1 and at least three rows
  /// a band; else in the single-threaded order): each step then runs its steps 1-4 in one parallel region.
  [[nodiscard]] bool banded() const { return banded_; }
  /// Quads of a cut's springs that fit no band (their particles reach into another band of their parity):
  /// swept after the bands on one thread. The others are swept with the band of their rows.
  [[nodiscard]] std::size_t unbanded_cut_quads() const;
  /// A cut's springs its update left loose on several threads (loosen_cut_springs), not yet batched.
  [[nodiscard]] std::size_t loose_springs() const;
  /// Whether every two bands of one parity share no particle, the cuts' springs in them included: what lets
  /// them be swept at once. Reads every quad (for tests).
  [[nodiscard]] bool bands_independent() const;
  /// Number of long-range attachments in use (0 when disabled or nothing is pinned).
  [[nodiscard]] std::size_t attachment_count() const;
  /// Full cache builds so far (the first step's included), and incremental updates after cuts.
  [[nodiscard]] std::size_t full_builds() const { return full_builds_; }
  [[nodiscard]] std::size_t incremental_updates() const { return incremental_updates_; }
  /// Pin groups of the long-range attachments (one search each): each particle has a tether per group.
  [[nodiscard]] std::size_t pin_groups() const { return pin_groups_.size(); }
  /// Rest length of the shortest path along the cloth's springs from pin group `group` to `particle`
  /// (+inf: none, or a repair after a cut has not settled it yet). What its tether is measured from.
  [[nodiscard]] float pin_distance(std::size_t group, std::uint32_t particle) const;
  /// Whether a repair of the attachments after a cut is still going on (it goes on within each step), the
  /// cut's own work (cut_work_per_step) included.
  [[nodiscard]] bool repairing() const;
  /// Whether a cut's tether work is still spread over the coming steps (SolverParams::cut_work_per_step).
  [[nodiscard]] bool cut_work_pending() const { return cut_phase_ != CutPhase::None; }
  /// Steps a cut's tether work takes at most: past them the rest is done in one step. A stroke cuts on
  /// every step, and each cut restarts the labelling, so without a bound a long stroke's cut-off pieces
  /// would hang on their old tethers until the hand stopped.
  static constexpr int kMaxCutWorkSteps = 12;
  /// Particles the repairs still have to settle, counted once per pin group whose repair has them open.
  [[nodiscard]] std::size_t open_particles() const;
  /// Entries in the repairs' lists of open particles, over all pin groups: what the next cut reads.
  [[nodiscard]] std::size_t repair_list_entries() const;

  /// A live spring copied out of the Cloth arrays, in the solver's sweep order.
  struct PackedSpring {
    std::uint32_t a;
    std::uint32_t b;
    float rest;
  };
  /// Four springs that share no particle, projected together (SSE lanes). Particle indices are stored
  /// plus one: index 0 is a particle that never moves, used by padding lanes and blanked (cut) springs.
  struct SpringQuad {
    std::array<std::uint32_t, 4> a;
    std::array<std::uint32_t, 4> b;
    alignas(16) float rest2[4];  ///< squared rest lengths
  };

 private:
  /// Where a spring sits in the batches.
  struct Slot {
    std::uint32_t quad = 0xFFFFFFFFU;
    std::uint8_t lane = 0;
    std::uint8_t family = 0;
  };
  static constexpr std::size_t kNoScan = static_cast<std::size_t>(-1);
  /// Marks a particle a cut made in PinGroup::unchecked (particle indices stay below 2^31).
  static constexpr std::uint32_t kFreshParticle = 1U << 31U;
  /// What a pin group's repair or opening pass, run on a thread of its own (Solver::run_apart), would have
  /// written to the solver's shared state: kept here, applied after in group order.
  struct Apart {
    bool active = false;
    std::vector<std::uint32_t> opened;    ///< particles opened (opened_)
    std::vector<std::uint32_t> engaging;  ///< tethers to tighten (engaging_)
    bool order_stale = false;             ///< a tether's bends changed (tether_order_stale_)
    std::size_t settled_from = 0;         ///< where this run's settles begin in `order` (their nearest pin)
    bool done = false;                    ///< the pass or repair finished
    std::size_t used = 0;                 ///< budget it used
  };
  /// A pin group of the long-range attachments (one pin when there are few, else an end or a half of the
  /// pinned line: build_attachments) with its shortest-path tree over the springs (Dijkstra, search_paths) and
  /// the state of its repair after a cut.
  struct PinGroup {
    std::vector<std::uint32_t> sources;
    std::vector<float> dist;
    std::vector<std::uint32_t> parent;     ///< previous particle on the shortest path (none at a source)
    std::vector<std::uint32_t> parent_spring;  ///< the spring from the parent (none at a source)
    std::vector<std::uint32_t> owner;      ///< the pin the path starts at
    std::vector<std::uint32_t> attachment; ///< per particle: its attachment in attachments_, or none
    /// Per particle: what its tether holds it to (the pin, or the last particle before the shortest path
    /// bends around a cut), and how many bends that is from the pin (0: held by the pin itself).
    std::vector<std::uint32_t> anchor;
    std::vector<std::uint32_t> bends;
    /// Per particle: the particle nearest to it on its path, past its anchor and before itself, where a path can
    /// bend around a cut (none: not known; kNoBend: there is none, checked at topology version bend_checked).
    /// Filled in only where a path bends, by the walk that looks for it (Solver::nearest_bend), so that the
    /// next particle whose path bends there stops its walk at the first particle that knows.
    std::vector<std::uint32_t> last_bend;
    std::vector<std::uint32_t> bend_checked;
    // A repair after a cut, possibly spread over several steps: its heap, the particles whose distance is
    // not final yet (their old tethers are kept meanwhile), and the same as a list.
    std::vector<std::pair<float, std::uint32_t>> heap;
    std::vector<std::uint8_t> open;
    std::vector<std::uint32_t> open_list;
    std::size_t open_count = 0;  ///< particles open now (open_list also lists those settled again since)
    std::size_t seeded = 0;  ///< open_list entries whose distances from settled neighbours are in the heap
    /// The settled particles in the order they settled, so each after its parent (the tree's edges point
    /// backwards); re-settled ones are appended and their old entries go stale (order_pos tells). A cut's
    /// orphaned subtrees are then one pass over the array from the first orphan, with no adjacency walks.
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> order_pos;  ///< per particle: its live place in order (none: not settled)
    /// Where the pass over `order` that opens a cut's orphaned subtrees goes on (none: no pass to make).
    std::size_t scan_from = kNoScan;
    /// The particles the cuts touched that this group has yet to look at, from `unchecked_from` on: whether
    /// the cut took the spring to their parent (an orphan, opened, and the pass above starts at it), or are
    /// new (kFreshParticle set: opened). The first part of the pass, so it is a cut's work too.
    std::vector<std::uint32_t> unchecked;
    std::size_t unchecked_from = 0;
    /// While the groups work at once on several threads (run_apart): what the group would write to the
    /// solver's shared state, applied after in group order.
    Apart apart;
    std::vector<std::uint32_t> reopen_subtree;  ///< scratch of reopen_shorter
  };
  /// A cut's tether work, in the order it is done: the orphans' subtrees opened (per pin group), then what the
  /// cut separated from a pin group found by floods from the touched particles and, past their cap, by
  /// union-find over the springs (its passes: each particle's bits, the springs, the roots), then released.
  enum class CutPhase : std::uint8_t { None, Open, Flood, Bits, Unite, Fold, Release };

  void refresh_caches(const Cloth& cloth);
  void full_build(const Cloth& cloth, std::vector<std::uint32_t> pins);
  void update_incrementally(const Cloth& cloth);
  /// Batches `springs` after each family's quads, in sweep order (ties by spring index; passed in increasing
  /// index, as every caller does, they are counted into place, otherwise sorted).
  void append_springs(const Cloth& cloth, const std::vector<std::uint32_t>& springs);
  /// append_springs for one family (0 structural, 1 shear, 2 bend): it touches only that family's quads and
  /// scratch and its springs' slots, so families may be batched on different threads.
  void append_family(const Cloth& cloth, const std::vector<std::uint32_t>& springs, std::size_t family);
  void order_strain_limit(const Cloth& cloth);
  void build_attachments(const Cloth& cloth);
  /// Settles at most `budget` particles and takes what it settled off it.
  bool search_paths(const Cloth& cloth, PinGroup& group, bool repair, std::size_t& budget);
  void continue_repairs(const Cloth& cloth);
  void refresh_nearest(std::uint32_t i);
  /// `engage`: a repair's tether, which holds the particle where it is and tightens over steps (engage_tethers).
  void attach(const Cloth& cloth, PinGroup& group, std::uint32_t i, bool engage);
  static std::uint32_t nearest_bend(const Cloth& cloth, PinGroup& group, std::uint32_t from, std::uint32_t anchor);
  void open_particle(PinGroup& group, std::uint32_t i);
  static void seed(const Cloth& cloth, PinGroup& group, std::uint32_t i);
  static void compact_order(PinGroup& group, std::size_t particles);
  /// A settled particle the repair found a shorter way to (an exact cut's shortcut): opened again with its
  /// subtree.
  void reopen_shorter(const Cloth& cloth, PinGroup& group, std::uint32_t root);
  static void compact_open_list(PinGroup& group);
  [[nodiscard]] static bool parent_spring_intact(const Cloth& cloth, PinGroup& group, std::uint32_t i);
  /// A cut's immediate part of the attachments' update: the arrays grown to the new particles, the particles
  /// whose path to the parent the cut broke opened; their subtrees are left to advance_cut_work.
  void update_attachments(const Cloth& cloth, const std::vector<std::uint32_t>& touched);
  /// Goes on with the cuts' tether work within `budget` visits (SIZE_MAX: to the end). Returns true when done.
  bool advance_cut_work(const Cloth& cloth, std::size_t budget);
  /// The subtrees of the orphans: one pass over each group's settle order (update_attachments). Returns the
  /// budget left, or nothing when it ran out first.
  std::optional<std::size_t> open_subtrees(const Cloth& cloth, std::size_t budget);
  /// One group's part of it; takes what it used off `budget`. Returns true when the group's pass is done.
  bool open_group_subtrees(const Cloth& cloth, PinGroup& group, std::size_t& budget);
  /// The pin groups for which `wanted(group)` holds, by index (in apart_groups_, until the next call).
  template <typename Wanted>
  const std::vector<std::size_t>& groups_where(const Wanted& wanted);
  /// Runs `work(group)` on each of `groups` at once (params_.threads), each group's shared writes kept apart.
  template <typename Work>
  void run_apart(const std::vector<std::size_t>& groups, const Work& work);
  std::vector<std::size_t> apart_groups_;  ///< scratch of groups_where
  /// Returns whether every open particle's verdict is in (else the components are labelled instead).
  bool release_cut_off(const Cloth& cloth, const std::vector<std::uint32_t>& touched);
  /// Particle i has no path to `group` any more: its tether of that group goes (kept disabled,
  /// anchored on itself, so that the step reads a valid index).
  void drop_tether(const PinGroup& group, std::uint32_t i);
  void release(PinGroup& group, std::uint32_t i);
  /// A bit per pin group: the ones particle i is open in, and the ones it is settled in (reached).
  [[nodiscard]] std::uint32_t open_groups(std::uint32_t i) const;
  [[nodiscard]] std::uint32_t settled_groups(std::uint32_t i) const;
  static void pack_quads(const std::vector<PackedSpring>& springs, const std::vector<std::uint32_t>& keys,
                           std::vector<SpringQuad>& quads);
  /// Splits each family's batches, as fully built, into 2 x threads bands of rows that share no particle with
  /// the other bands of their parity (none: too few rows, or a band's particles reach past its neighbour).
  void build_bands(const Cloth& cloth);
  /// Gives quads_[family]'s quads from `first` on (a cut's, just appended, in row order) to the band of
  /// their rows where that keeps the band apart from the others of its parity, else to the unbanded tail.
  void place_cut_quads(const Cloth& cloth, std::size_t family, std::size_t first);
  /// The band whose reach holds grid rows [low, high] (the band of `low`'s rows, if its reach takes in `high`),
  /// else band_reach_.size(): after the bands. The one rule of place_cut_quads and loosen_cut_springs.
  std::size_t band_of_rows(int low, int high) const;
  /// A band's batches, then the cut's quads placed in it, in the order they came.
  void sweep_band(Eigen::Vector4f* padded, std::size_t family, std::size_t band, float alpha) const;
  /// The cut's quads that fit no band, in the order they came (one thread, after the bands).
  void sweep_unbanded(Eigen::Vector4f* padded, std::size_t family, float alpha) const;
  /// On several threads in bands: the update's part of a cut's springs (the live ones among `edited`, every
  /// family), listed in the band of their rows and swept one by one (loose_bands_), not batched
  /// (loosen_cut_springs). The next step batches them (fold_loose_springs, at its start, before any update
  /// reads their slots).
  void loosen_cut_springs(const Cloth& cloth, const std::vector<std::uint32_t>& edited);
  void fold_loose_springs(const Cloth& cloth);
  /// Returns whether it also read which springs are over `limit` into limit_dirty_ (limit > 0, no cut's
  /// springs after the bands).
  template <typename Predict>
  bool front_in_bands(Eigen::Vector4f* x, std::size_t n, const Predict& predict, bool soft, float shear_alpha,
                      float bend_alpha, float structural_alpha, float limit);
  /// One XPBD pass over a family of springs (substep steps 3 and 4) in the single-threaded order; when the
  /// springs are banded, front_in_bands sweeps them instead.
  void sweep_springs(Eigen::Vector4f* padded, std::size_t family, float alpha) const;
  /// Step 2 over every tether, in the order they apply: in parallel over each pin group's block.
  void sweep_all_tethers(Eigen::Vector4f* x) const;
  /// Sets limit_dirty_ to a bit per place in strain_limit_ whose spring is over `limit` now, on all threads.
  void mark_over_limit(const Eigen::Vector4f* x, float limit);
  void mark_word(const Eigen::Vector4f* x, float limit, std::size_t word);
  /// One sub-step; on several threads in bands (banded()) its step 6 is finished by the next one, the last
  /// one's with the positions written back to the cloth.
  void substep(Cloth& cloth, const Colliders& colliders, float h, bool first, bool last_substep);
  /// Substep step 5, Provot's deformation constraint: full passes, then sparse ones, then local ones
  /// (strain_limit.cpp). `premarked`: front_in_bands already read which springs are over the limit.
  void limit_strain(const Cloth& cloth, Eigen::Vector4f* x, bool premarked);
  /// Provot's sweeps past their budget, over only the springs near the last corrections (substep step 5).
  template <typename LimitSpring>
  void limit_locally(const Cloth& cloth, const LimitSpring& limit_spring);
  static constexpr int kLocalLimitPasses = 100;  ///< besides the cap on visits (kLocalLimitVisitsPerPass)
  /// The local passes' visits in all: at most a full pass's springs divided by this.
  static constexpr std::size_t kLocalLimitVisitsPerPass = 8;
  /// Whether the last strain-limit pass corrected few enough springs (a thirty-second) to go on locally.
  [[nodiscard]] bool few_limit_corrections() const { return limit_active_.size() * 32 <= strain_limit_.size(); }
  /// A strain-limit pass that has marked more than this share (1/N) of the springs for the next one stops
  /// marking: the next pass reads every spring (substep step 5; marking costs ~20 reads per correction).
  static constexpr std::size_t kSparseLimitShare = 16;

  SolverParams params_;
  // Cache key.
  std::uint32_t cached_version_ = 0;
  std::size_t cached_springs_ = 0;
  std::size_t cached_particles_ = 0;
  std::size_t edits_read_ = 0;
  std::vector<std::uint32_t> cached_pins_;
  bool cache_valid_ = false;
  std::size_t full_builds_ = 0;
  std::size_t incremental_updates_ = 0;
  std::array<std::vector<SpringQuad>, 3> quads_;  ///< structural, shear, bend, four at a time
  /// Per family: where each band of rows starts in quads_ (2 x threads + 1 bounds; empty: sweep in order),
  /// over the batches of the last full build (a cut's springs, appended after them, are swept with the band
  /// of their rows or after the bands: band_cut_runs_, unbanded_runs_).
  std::array<std::vector<std::size_t>, 3> bands_;
  bool banded_ = false;
  /// A run of quads_ entries [begin, end).
  struct QuadRun {
    std::uint32_t begin;
    std::uint32_t end;
  };
  /// Per family and band: the runs of a cut's quads swept with that band (place_cut_quads); per family, the
  /// runs that fit no band. Per band: its first row, and the rows a cut's quad in it may reach (apart from
  /// every other band of its parity; build_bands).
  std::array<std::vector<std::vector<QuadRun>>, 3> band_cut_runs_;
  std::array<std::vector<QuadRun>, 3> unbanded_runs_;
  /// The last cut's springs, not yet batched (loosen_cut_springs): their indices in increasing order, and per
  /// family and band (the last entry: those that fit no band) their ends (plus one, as in a quad) and rest
  /// lengths, in that order; whether a step has swept them (the next refresh_caches then batches them).
  std::vector<std::uint32_t> loose_springs_;
  std::array<std::vector<std::vector<PackedSpring>>, 3> loose_bands_;
  bool loose_swept_ = false;
  std::vector<int> band_first_row_;
  std::vector<std::pair<int, int>> band_reach_;
  /// Where each pin group's block of tethers ends in attachments_, as the full build made them (in a block
  /// every tether holds a different particle; those with no bend hang on a pin, which never moves).
  std::vector<std::size_t> tether_block_end_;
  std::size_t unbent_tethers_ = 0;  ///< leading entries of tether_order_ with no bend (when it is in use)
  std::vector<Slot> slot_;                    ///< per spring
  /// Scratch of append_family, one per family: the family's springs in the order given and their sweep keys;
  /// in sweep order, their keys, their ends, their quads; the counting sort's counts.
  struct BatchScratch {
    std::vector<std::uint32_t> springs;
    std::vector<std::uint32_t> keys;
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> sorted_keys;
    std::vector<PackedSpring> packed;
    std::vector<SpringQuad> fresh;
    std::vector<std::uint32_t> count;
  };
  std::array<BatchScratch, 3> batch_scratch_;
  std::size_t lanes_ = 0;                     ///< lanes in use when last fully built, and blanked since
  std::size_t blanked_ = 0;
  // Structural springs again, ordered outwards from the pins, for the strain limit; per spring its place
  // there (none for other kinds); whether a cut appended to it since it was last ordered, and whether it is
  // to be re-ordered on a step with no cut (the cut's repair finished within its own step).
  std::vector<PackedSpring> strain_limit_;
  std::vector<std::uint32_t> limit_slot_;
  /// Places in strain_limit_ of the springs shorter than a cell (an exact cut's), swept again after each pass.
  std::vector<std::uint32_t> limit_again_;
  // Scratch of limit_locally: the places corrected by the last pass, the next pass's places, and a mark
  // per place (cleared after each pass).
  std::vector<std::uint32_t> limit_active_;
  std::vector<std::uint32_t> limit_next_;
  std::vector<std::uint8_t> limit_mark_;
  /// A bit per place in strain_limit_: a correction moved an end of that spring since its last check.
  std::vector<std::uint64_t> limit_dirty_;
  bool limit_order_stale_ = false;
  bool pending_limit_order_ = false;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> limit_level_;  // scratch: (level, spring)
  std::vector<PackedSpring> limit_packed_;  // scratch: the same springs packed, nearer end first
  std::vector<std::uint32_t> limit_start_;
  // Long-range attachments: particle, anchor (a pin, or a particle at a bend of the shortest path around
  // a cut), maximal distance.
  struct Attachment {
    std::uint32_t particle;
    std::uint32_t anchor;
    float length2;  ///< squared maximal distance (+inf: disabled, the pin no longer reaches it)
    std::uint32_t bends;  ///< applied after every attachment with fewer bends (its anchor's own tether)
    float reach2 = 0.0F;  ///< squared distance held now: from where the particle was when the tether came, down to length2
  };
  std::vector<std::uint32_t> engaging_;  ///< attachments whose reach is still above their length
  std::vector<Attachment> attachments_;
  std::vector<std::uint32_t> tether_order_;  ///< attachments by bends; empty while none bends
  bool tether_order_stale_ = false;
  /// Scratch of order_tethers' counting sort: per thread's chunk, per key.
  std::vector<std::vector<std::uint32_t>> sort_scratch_;
  void order_tethers();
  void engage_tethers();
  std::vector<PinGroup> pin_groups_;
  std::vector<float> nearest_;  ///< per particle: rest distance to the nearest pin (+inf: no pin reaches it)
  std::vector<std::uint32_t> opened_;  ///< scratch of the incremental update: particles it opened, once each
  std::vector<std::uint8_t> opened_mark_;  ///< per particle: in opened_ (cleared after each update)
  // Scratch of release_cut_off: per particle 0 (not flooded), 1 (in the flood going on), 2 (flooded
  // before in this update); the flooded particles in order, component after component.
  std::vector<std::uint8_t> flood_seen_;
  std::vector<std::uint32_t> flood_visited_;
  // Scratch of the labelling by union-find (advance_cut_work): per particle the pin groups it is open in, the ones it is
  // settled in, the groups it meets (then per component root), and the union-find parent.
  std::vector<std::uint8_t> flood_open_;
  std::vector<std::uint8_t> flood_settled_;
  std::vector<std::uint8_t> flood_met_;
  UnionFind<std::uint32_t> flood_sets_;
  // Scratch of the incremental update: a bit per spring (edited by the cut) and per particle (touched by the
  // edited springs), cleared as read; the same once each, in increasing order.
  std::vector<std::uint64_t> edited_bits_;
  std::vector<std::uint64_t> touched_bits_;
  // The second thread's marks, while the update reads the edits on two threads.
  std::vector<std::uint64_t> edited_bits_apart_;
  std::vector<std::uint64_t> touched_bits_apart_;
  std::vector<std::uint32_t> edited_;
  std::vector<std::uint32_t> touched_;
  // The cuts' tether work spread over steps (advance_cut_work): its phase, the particles every cut since it
  // began touched (sorted, once each), where the phase's pass is, and the steps it has taken.
  CutPhase cut_phase_ = CutPhase::None;
  std::vector<std::uint32_t> cut_touched_;
  std::size_t cut_cursor_ = 0;
  int cut_work_steps_ = 0;
  std::size_t repair_turn_ = 0;  ///< the pin group whose repair goes first this step (they take turns)
  bool cut_work_fresh_ = false;  ///< left over by this step's cut (its update did this step's slice)
  void clear_cut_work();
  /// The visits the cut's work has left, as advance_cut_work counts them (the release pass not included).
  [[nodiscard]] std::size_t cut_work_left(const Cloth& cloth) const;
  // Positions with the inverse mass in w, during a step; element 0 is the fixed padding particle.
  std::vector<Eigen::Vector4f> work_;
  std::vector<Eigen::Vector4f> old_work_;
};

/// Total mechanical energy (kinetic + gravitational potential relative to y = 0 + spring potential of
/// stretched structural springs with stiffness k_structural), for tests that check energy does not grow.
[[nodiscard]] double mechanical_energy(const Cloth& cloth, const Eigen::Vector3f& gravity, double k_structural);

}  // namespace tachi::sim
