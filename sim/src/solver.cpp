#include "tachi/sim/solver.hpp"

#include <emmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <thread>
#include <utility>

namespace tachi::sim {

namespace {

/// Sweep position of a spring: its upper row, then a colour such that two springs of one row and
/// colour never share a particle. Sweeping row by row keeps the few rows being worked on in cache
/// (256^2 positions are 1 MB), and inside a row consecutive projections are independent, so the CPU
/// overlaps them; the sweep as a whole stays plain Gauss-Seidel in a fixed order.
std::uint32_t sweep_key(SpringKind k, GridCoord a, GridCoord b) {
  constexpr int kColoursPerRow = 8;
  const int umin = std::min(a.u, b.u);
  const int vmin = std::min(a.v, b.v);
  const bool along_row = a.v == b.v;
  int colour = 0;
  switch (k) {
    case SpringKind::Structural:
      colour = along_row ? umin % 2 : 2;  // (u, u+1) alternate; columns of one row never touch
      break;
    case SpringKind::Shear:
      colour = (b.u - a.u) * (b.v - a.v) > 0 ? 0 : 1;  // diagonals, then anti-diagonals
      break;
    case SpringKind::Bend:
      colour = along_row ? umin % 4 : 4;  // (u, u+2) share ends with (u+2, u+4): four classes
      break;
  }
  return static_cast<std::uint32_t>(vmin * kColoursPerRow + colour);
}

/// Runs body(begin, end) over [0, n) in `threads` contiguous chunks at once (OpenMP, static: chunk t on
/// thread t), or in one call for one thread or a short range. For loops whose iterations are independent
/// (each particle on its own, or tethers of distinct particles), so the results do not depend on the split.
template <typename Body>
void for_chunks(std::size_t n, int threads, const Body& body) {
  constexpr std::size_t kWorthSplitting = 2048;  // below this the threads' wake-up costs more than the loop
  if (threads <= 1 || n < kWorthSplitting) {
    body(std::size_t{0}, n);
    return;
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int t = 0; t < threads; ++t) {
    const auto chunk = static_cast<std::size_t>(t);
    const auto parts = static_cast<std::size_t>(threads);
    body(n * chunk / parts, n * (chunk + 1) / parts);
  }
}

}  // namespace

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
  if (p.threads < 1 || p.threads > 64) return "threads must be in [1, 64]";
  return std::nullopt;
}

int default_solver_threads() {
  const unsigned cores = std::thread::hardware_concurrency();
  return cores <= 1 ? 1 : static_cast<int>(std::min(cores - 1, 64U));
}

Solver::Solver(SolverParams params) : params_(std::move(params)) {}

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFU;
constexpr std::uint32_t kNoBend = 0xFFFFFFFEU;  // Search::last_bend: checked, there is none
constexpr float kInf = std::numeric_limits<float>::infinity();

/// Whether a search has settled a particle, from its open flag and distance: reached, and not open for repair.
/// (Solver::seed reads only settled neighbours; settled_groups and the labelling of cut-off pieces use it.)
constexpr bool settled(std::uint8_t open, float dist) { return open == 0 && dist < kInf; }

/// Octile distance between two rest coordinates (cells): the length of the shortest path along a
/// grid's structural and shear springs, which Dijkstra over an uncut grid measures.
float octile(const Cloth& cloth, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  const float du = std::abs(a.x() - b.x());
  const float dv = std::abs(a.y() - b.y());
  const float diagonal = std::min(du, dv);
  return (du - diagonal) * cloth.spacing_x() + (dv - diagonal) * cloth.spacing_y() +
         diagonal * std::hypot(cloth.spacing_x(), cloth.spacing_y());
}

/// Distance (m) of particle p's rest coordinate from the nearest grid point: 0 for a grid particle.
float off_grid(const Cloth& cloth, std::uint32_t p) {
  const Eigen::Vector2f& uv = cloth.rest_uv[p];
  const float du = (uv.x() - std::round(uv.x())) * cloth.spacing_x();
  const float dv = (uv.y() - std::round(uv.y())) * cloth.spacing_y();
  return std::sqrt(du * du + dv * dv);
}

/// Whether a shortest path in the cloth's rest plane can bend at particle p: p is on the boundary (one of its
/// edges borders a single triangle) and the piece's angle there, the sum of its triangles' angles at p in rest
/// coordinates, exceeds 180 degrees (a cut's tip: 360; a corner of a staircase cut: 270). Only there does a
/// geodesic wrap around the cut; along a straight lip (180) or inside the cloth (360, no boundary) it runs
/// straight. The 10 degree margin keeps the float rounding of a straight lip's rest coordinates out.
bool is_bend_point(const Cloth& cloth, std::uint32_t p) {
  constexpr float kReflex = 3.14159265F * (1.0F + 10.0F / 180.0F);
  constexpr std::size_t kFan = 32;  // neighbours in p's fan (a grid particle has 6, an exact cut adds a few)
  std::array<std::uint32_t, kFan> neighbour{};
  std::array<std::uint8_t, kFan> edges{};  // how many of p's triangles share the edge p-neighbour
  std::size_t count = 0;
  const auto see = [&](std::uint32_t q) {
    for (std::size_t k = 0; k < count; ++k) {
      if (neighbour[k] == q) {
        ++edges[k];
        return;
      }
    }
    if (count < kFan) {
      neighbour[count] = q;
      edges[count++] = 1;
    }
  };
  // Called up a path that fails the straightness test (Solver::nearest_bend): the boundary test (integers)
  // first, the angles only on the boundary.
  const auto corners = [&](std::uint32_t t) {
    const auto& tri = cloth.triangles[t];
    const std::size_t at = tri[0] == p ? 0 : tri[1] == p ? 1 : 2;
    return std::pair{tri[(at + 1) % 3], tri[(at + 2) % 3]};
  };
  for (const std::uint32_t t : cloth.triangles_of(p)) {
    const auto [q, r] = corners(t);
    see(q);
    see(r);
  }
  if (std::none_of(edges.begin(), edges.begin() + static_cast<std::ptrdiff_t>(count),
                   [](std::uint8_t e) { return e == 1; })) {
    return false;
  }
  const Eigen::Vector2f scale{cloth.spacing_x(), cloth.spacing_y()};
  float angle = 0.0F;
  for (const std::uint32_t t : cloth.triangles_of(p)) {
    const auto [q, r] = corners(t);
    const Eigen::Vector2f a = (cloth.rest_uv[q] - cloth.rest_uv[p]).cwiseProduct(scale);
    const Eigen::Vector2f b = (cloth.rest_uv[r] - cloth.rest_uv[p]).cwiseProduct(scale);
    angle += std::atan2(std::abs(a.x() * b.y() - a.y() * b.x()), a.dot(b));
  }
  return angle > kReflex;
}

}  // namespace

std::size_t Solver::attachment_count() const {
  return static_cast<std::size_t>(std::count_if(attachments_.begin(), attachments_.end(),
                                                [](const Attachment& a) { return std::isfinite(a.length2); }));
}

float Solver::pin_distance(std::size_t group, std::uint32_t particle) const {
  if (group >= searches_.size() || particle >= searches_[group].dist.size()) return kInf;
  const Search& search = searches_[group];
  return search.open[particle] != 0 ? kInf : search.dist[particle];
}

std::size_t Solver::open_particles() const {
  std::size_t open = 0;
  for (const Search& search : searches_) open += search.open_count;
  return open;
}

std::size_t Solver::repair_list_entries() const {
  std::size_t entries = 0;
  for (const Search& search : searches_) entries += search.open_list.size();
  return entries;
}

bool Solver::repairing() const {
  return std::any_of(searches_.begin(), searches_.end(),
                     [](const Search& s) { return !s.heap.empty() || !s.open_list.empty(); });
}

void Solver::build_groups(const std::vector<PackedSpring>& springs, const std::vector<std::uint32_t>& keys,
                          std::vector<Group>& groups) {
  // Four springs of one sweep class (same row and colour) never share a particle on the grid; the check
  // below also keeps that true for springs a cut added or rewired, so the four lanes stay independent.
  Group g{};
  int lanes = 0;
  std::uint32_t group_key = 0;
  auto flush = [&] {
    if (lanes == 0) return;
    for (int l = lanes; l < 4; ++l) {
      g.a[l] = 0;  // padding lane: the fixed particle 0 on both ends does nothing
      g.b[l] = 0;
      g.rest2[l] = 1.0F;
    }
    groups.push_back(g);
    lanes = 0;
  };
  for (std::size_t k = 0; k < springs.size(); ++k) {
    const PackedSpring& sp = springs[k];
    const std::uint32_t a = sp.a + 1;
    const std::uint32_t b = sp.b + 1;
    bool clash = lanes > 0 && keys[k] != group_key;
    for (int l = 0; l < lanes && !clash; ++l) clash = g.a[l] == a || g.a[l] == b || g.b[l] == a || g.b[l] == b;
    if (clash) flush();
    if (lanes == 0) group_key = keys[k];
    g.a[lanes] = a;
    g.b[lanes] = b;
    g.rest2[lanes] = sp.rest * sp.rest;
    if (++lanes == 4) flush();
  }
  flush();
}

void Solver::refresh_caches(const Cloth& cloth) {
  // Anchors: every particle that does not move by itself, pinned or held by the hand (a held particle
  // drags the cloth like a pin, so it gets attachments and the strain limit sweeps out from it too).
  // The same anchors as cached: as many particles with no inverse mass as cached pins, and each of those
  // still one (distinct indices, so the sets are equal). Counted, not listed: this runs every step, and
  // listing them cost a 256 x 256 step ~0.6M instructions.
  std::size_t anchors = 0;
  for (const float w : cloth.inverse_mass) anchors += w == 0.0F ? 1U : 0U;
  const bool pins_same =
      cache_valid_ && anchors == cached_pins_.size() &&
      std::all_of(cached_pins_.begin(), cached_pins_.end(),
                  [&](std::uint32_t i) { return i < cloth.particle_count() && cloth.inverse_mass[i] == 0.0F; });
  const bool topology_same = cache_valid_ && cached_version_ == cloth.topology_version &&
                             cached_springs_ == cloth.spring_count() &&
                             cached_particles_ == cloth.particle_count();
  if (topology_same && pins_same) return;
  // Incremental only when the change is one the cloth logged: springs edited through its functions and
  // particles appended. Anything else (new pins, a grab, arrays edited directly) is rebuilt in full.
  const bool logged = pins_same && cloth.spring_edits.size() > edits_read_ &&
                      cloth.spring_count() >= cached_springs_ && cloth.particle_count() >= cached_particles_;
  if (logged) {
    update_incrementally(cloth);
  } else {
    std::vector<std::uint32_t> pins;
    pins.reserve(anchors);
    for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
      if (cloth.inverse_mass[i] == 0.0F) pins.push_back(static_cast<std::uint32_t>(i));
    }
    full_build(cloth, std::move(pins));
  }
  // Blanked lanes still cost a load and a store each: past half the batches, compact them.
  if (blanked_ * 2 > lanes_) full_build(cloth, cached_pins_);
  cached_version_ = cloth.topology_version;
  cached_springs_ = cloth.spring_count();
  cached_particles_ = cloth.particle_count();
  edits_read_ = cloth.spring_edits.size();
  cache_valid_ = true;
}

void Solver::full_build(const Cloth& cloth, std::vector<std::uint32_t> pins) {
  ++full_builds_;
  for (auto& g : groups_) g.clear();
  // As much room as the cloth reserved for its cuts (Cloth::reserve): the first cut then grows the solver's
  // per-particle arrays in place instead of reallocating (and faulting in) every one of them at once, which
  // made the step of the first cut at 256 x 256 take ~50 ms.
  const std::size_t particle_room = cloth.position.capacity() + 1;
  reserve_touched(nearest_, particle_room);
  reserve_touched(opened_, particle_room);
  reserve_touched(opened_mark_, particle_room);
  reserve_touched(touched_mark_, particle_room);
  reserve_touched(flood_seen_, particle_room);
  // release_cut_off_by_components sizes its scratch to the cloth on every call, and a cut adds particles.
  reserve_touched(flood_open_, particle_room);
  reserve_touched(flood_settled_, particle_room);
  reserve_touched(flood_met_, particle_room);
  reserve_touched(flood_parent_, particle_room);
  reserve_touched(work_, particle_room);
  reserve_touched(old_work_, particle_room);
  reserve_touched(slot_, cloth.spring_a.capacity());
  reserve_touched(limit_slot_, cloth.spring_a.capacity());
  slot_.assign(cloth.spring_count(), Slot{});
  lanes_ = 0;
  blanked_ = 0;
  std::vector<std::uint32_t> all;
  all.reserve(cloth.spring_count());
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] != 0) all.push_back(k);
  }
  cached_pins_ = std::move(pins);
  build_attachments(cloth);
  append_springs(cloth, all);
  build_bands(cloth);
  order_strain_limit(cloth);
  lanes_ = 0;
  for (auto& g : groups_) {
    lanes_ += 4 * g.size();
    reserve_touched(g, g.size() + g.size() / 4);  // the cuts' springs are appended (compacted past half blanked)
  }
  reserve_touched(strain_limit_, strain_limit_.size() + strain_limit_.size() / 4);
}

void Solver::append_springs(const Cloth& cloth, const std::vector<std::uint32_t>& springs) {
  // Sorted by (family, sweep key, spring index): a counting sort would be linear, but the keys of a full
  // build are few per row and a cut's springs are few, so std::sort on packed 64-bit keys is as fast.
  std::array<std::vector<std::uint64_t>, 3> order;
  for (const std::uint32_t k : springs) {
    if (cloth.alive[k] == 0) continue;
    const std::uint32_t key = sweep_key(cloth.kind[k], cloth.grid[cloth.spring_a[k]], cloth.grid[cloth.spring_b[k]]);
    order[static_cast<std::size_t>(cloth.kind[k])].push_back((static_cast<std::uint64_t>(key) << 32U) | k);
  }
  std::vector<PackedSpring> packed;
  std::vector<std::uint32_t> keys;
  std::vector<Group> fresh;
  for (std::size_t f = 0; f < 3; ++f) {
    std::sort(order[f].begin(), order[f].end());
    packed.clear();
    keys.clear();
    for (const std::uint64_t e : order[f]) {
      const auto k = static_cast<std::uint32_t>(e & 0xFFFFFFFFU);
      packed.push_back({cloth.spring_a[k], cloth.spring_b[k], cloth.rest_length[k]});
      keys.push_back(static_cast<std::uint32_t>(e >> 32U));
    }
    fresh.clear();
    build_groups(packed, keys, fresh);
    // Find where each spring landed (build_groups keeps the order, filling lanes in sequence).
    const auto base = static_cast<std::uint32_t>(groups_[f].size());
    std::size_t next = 0;
    for (std::uint32_t g = 0; g < fresh.size(); ++g) {
      for (std::uint8_t l = 0; l < 4 && next < order[f].size(); ++l) {
        const auto k = static_cast<std::uint32_t>(order[f][next] & 0xFFFFFFFFU);
        if (fresh[g].a[l] != cloth.spring_a[k] + 1 || fresh[g].b[l] != cloth.spring_b[k] + 1) continue;
        slot_[k] = {base + g, l, static_cast<std::uint8_t>(f)};
        ++next;
      }
    }
    groups_[f].insert(groups_[f].end(), fresh.begin(), fresh.end());
  }
}

void Solver::order_strain_limit(const Cloth& cloth) {
  // Outwards from the pins, by the rest distance of the spring's nearer end quantised to half a spacing,
  // ties in spring order (measured in docs/sim.md); pieces no pin holds (+inf) last. Redone after every
  // cut because a cut lengthens the distances behind it: a counting sort, linear in the springs.
  const float unit = 0.5F * std::min(cloth.spacing_x(), cloth.spacing_y());
  auto& level = limit_level_;
  level.clear();
  std::uint32_t top = 0;
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] != SpringKind::Structural) continue;
    const float d = std::min(nearest_[cloth.spring_a[k]], nearest_[cloth.spring_b[k]]);
    const std::uint32_t l = std::isfinite(d) ? static_cast<std::uint32_t>(d / unit) : kNone;
    if (l != kNone) top = std::max(top, l);
    level.emplace_back(l, k);
  }
  auto& start = limit_start_;
  start.assign(static_cast<std::size_t>(top) + 3, 0);
  for (auto& [l, k] : level) {
    if (l == kNone) l = top + 1;
    ++start[l + 1];
  }
  for (std::size_t l = 1; l < start.size(); ++l) start[l] += start[l - 1];
  strain_limit_.resize(level.size());
  limit_slot_.assign(cloth.spring_count(), kNone);
  for (const auto& [l, k] : level) {
    std::uint32_t na = cloth.spring_a[k];
    std::uint32_t nb = cloth.spring_b[k];
    if (nearest_[nb] < nearest_[na]) std::swap(na, nb);
    limit_slot_[k] = start[l];
    strain_limit_[start[l]++] = {na, nb, cloth.rest_length[k]};
  }
  // An exact cut's lip is a chain of structural springs 0.08-0.9 cells long between light particles. A pass
  // corrects a long one by moving its ends by up to a tenth of its length, which overstretches a short
  // neighbour by that much relative to ITS length: in place in the order, the short springs of a jittered
  // 64 x 64 slit needed 10 passes to settle within 10 % (6 left them at 12.7 %, and 10 cost a long stroke's
  // swinging steps +33 %). Swept again at the end of each pass, their corrections move their ends by a tenth of
  // a short length, little for the long ones: 6 passes settle them (9.99 %). Places, not copies, so that a
  // spring a later cut removes (its place blanked) is skipped here too.
  limit_again_.clear();
  const float short_spring = 0.9F * std::min(cloth.spacing_x(), cloth.spacing_y());
  for (std::uint32_t s = 0; s < strain_limit_.size(); ++s) {
    if (strain_limit_[s].rest < short_spring) limit_again_.push_back(s);
  }
  limit_order_stale_ = false;
}

void Solver::update_incrementally(const Cloth& cloth) {
  ++incremental_updates_;
  slot_.resize(cloth.spring_count(), Slot{});
  // The springs the cut edited, once each; the particles they touched before and after.
  std::vector<std::uint32_t> edited(cloth.spring_edits.begin() + static_cast<std::ptrdiff_t>(edits_read_),
                                    cloth.spring_edits.end());
  std::sort(edited.begin(), edited.end());
  edited.erase(std::unique(edited.begin(), edited.end()), edited.end());
  // Each touched particle once (a cut edits several springs of each): marked as it is met, so that only the
  // distinct ones are sorted (sorting every end of every edited spring was half of this update's time).
  std::vector<std::uint32_t> touched;
  touched_mark_.resize(cloth.particle_count(), 0);
  const auto touch = [&](std::uint32_t i) {
    if (touched_mark_[i] != 0) return;
    touched_mark_[i] = 1;
    touched.push_back(i);
  };
  for (const std::uint32_t k : edited) {
    Slot& s = slot_[k];
    if (s.group != kNone) {
      Group& g = groups_[s.family][s.group];
      touch(g.a[s.lane] - 1);
      touch(g.b[s.lane] - 1);
      g.a[s.lane] = 0;  // blanked: both ends on the fixed particle, so the lane does nothing
      g.b[s.lane] = 0;
      g.rest2[s.lane] = 1.0F;
      s = Slot{};
      ++blanked_;
    }
    if (cloth.alive[k] != 0) {
      touch(cloth.spring_a[k]);
      touch(cloth.spring_b[k]);
    }
  }
  for (std::size_t i = cached_particles_; i < cloth.particle_count(); ++i) touch(static_cast<std::uint32_t>(i));
  std::sort(touched.begin(), touched.end());
  for (const std::uint32_t i : touched) touched_mark_[i] = 0;
  update_attachments(cloth, touched);
  release_cut_off(cloth, touched);
  append_springs(cloth, edited);
  // The strain limit: the cut's springs leave their places (never over the limit: skipped) and its new
  // ones go last. Re-ordering outwards from the pins (the distances behind a cut grow) is linear in the
  // springs, so it waits for the attachments' repair to settle (continue_searches) or the next compaction.
  limit_slot_.resize(cloth.spring_count(), kNone);
  for (const std::uint32_t k : edited) {
    if (limit_slot_[k] != kNone) {
      strain_limit_[limit_slot_[k]].rest = kInf;
      limit_slot_[k] = kNone;
    }
    if (cloth.alive[k] == 0 || cloth.kind[k] != SpringKind::Structural) continue;
    std::uint32_t na = cloth.spring_a[k];
    std::uint32_t nb = cloth.spring_b[k];
    if (nearest_[nb] < nearest_[na]) std::swap(na, nb);
    limit_slot_[k] = static_cast<std::uint32_t>(strain_limit_.size());
    strain_limit_.push_back({na, nb, cloth.rest_length[k]});
  }
  limit_order_stale_ = true;
  if (!repairing()) pending_limit_order_ = true;
}

void Solver::seed(const Cloth& cloth, Search& search, std::uint32_t i) {
  // An open particle's distance through its settled neighbours, into the heap (the repair's start).
  for (const std::uint32_t k : cloth.springs_of(i)) {
    if (cloth.kind[k] == SpringKind::Bend) continue;
    const std::uint32_t j = cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
    if (!settled(search.open[j], search.dist[j])) continue;
    const float d = search.dist[j] + cloth.rest_length[k];
    if (d < search.dist[i]) {
      search.dist[i] = d;
      search.parent[i] = j;
      search.parent_spring[i] = k;
      search.owner[i] = search.owner[j];
    }
  }
  if (std::isfinite(search.dist[i])) {
    search.heap.emplace_back(search.dist[i], i);
    std::push_heap(search.heap.begin(), search.heap.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  }
}

bool Solver::run_search(const Cloth& cloth, Search& search, bool repair, std::size_t budget) {
  // Dijkstra over live structural and shear springs (rest lengths), at most `budget` particles settled per
  // call. A repair (after a cut) first seeds every open particle with its distance through its settled
  // neighbours (at most four times the budget per call), then relaxes only the open particles: the others' distances are final (a cut only
  // lengthens paths, so a particle whose shortest path the cut did not touch keeps it); each particle it
  // settles gets its tether back. Seeding is finished before anything settles, so no particle settles at a
  // distance a seed not yet in the heap would have shortened. Returns true when the search is complete.
  auto& heap = search.heap;
  const auto greater = [](const auto& x, const auto& y) { return x.first > y.first; };
  const auto neighbour = [&](std::uint32_t k, std::uint32_t i) {
    return cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
  };
  if (repair) {
    // Seeding is not counted against the budget: spread over steps it kept the tethers of a large opened
    // region off for twice as long, and the swinging cloth then met a long stroke folded (a 128 x 128 grid
    // stroke cut off a third piece of 856 particles).
    // Seeding costs less than settling (no heap pops): four times the budget. Counted against the budget
    // itself it kept the tethers of a large opened region off for twice as long, and the cloth swinging
    // under cut_bench's long stroke met it folded (a 128 x 128 grid stroke cut off a third piece).
    std::size_t seeds = 4 * budget;
    while (search.seeded < search.open_list.size() && seeds > 0) {
      const std::uint32_t i = search.open_list[search.seeded++];
      --seeds;
      if (search.open[i] != 0) seed(cloth, search, i);
    }
    if (search.seeded < search.open_list.size()) return false;
  }
  while (!heap.empty() && budget > 0) {
    std::pop_heap(heap.begin(), heap.end(), greater);
    const auto [d, i] = heap.back();
    heap.pop_back();
    if (d != search.dist[i]) continue;  // superseded: a shorter path came, or a later cut reset it
    if (repair) {
      if (search.open[i] == 0) continue;
      search.open[i] = 0;
      --search.open_count;
      refresh_nearest(i);
    }
    search.order_pos[i] = static_cast<std::uint32_t>(search.order.size());
    search.order.push_back(i);
    // In the order particles settle: a particle's anchor comes from its parent's, settled before it.
    if (params_.long_range_attachments) attach(cloth, search, i, repair);
    --budget;
    for (const std::uint32_t k : cloth.springs_of(i)) {
      if (cloth.kind[k] == SpringKind::Bend) continue;
      const std::uint32_t j = neighbour(k, i);
      const float dj = d + cloth.rest_length[k];
      if (repair ? search.open[j] == 0 : search.order_pos[j] != kNone) continue;
      if (dj < search.dist[j]) {
        search.dist[j] = dj;
        search.parent[j] = i;
        search.parent_spring[j] = k;
        search.owner[j] = search.owner[i];
        heap.emplace_back(dj, j);
        std::push_heap(heap.begin(), heap.end(), greater);
      }
    }
  }
  if (!heap.empty()) return false;
  // What the repair never reached is cut off from this pin: its tether, kept while it was open, goes.
  for (const std::uint32_t i : search.open_list) {
    if (search.open[i] != 0) release(search, i);
  }
  search.open_list.clear();
  search.seeded = 0;
  return true;
}

void Solver::compact_order(Search& search, std::size_t particles) {
  // Stale entries (particles that settled again) past half the order: dropped, the live ones keeping their
  // relative order (each still after its parent). Any time, a repair in progress included.
  if (search.order.size() <= 2 * particles) return;
  std::size_t live = 0;
  for (std::size_t pos = 0; pos < search.order.size(); ++pos) {
    const std::uint32_t i = search.order[pos];
    if (search.order_pos[i] != pos) continue;
    search.order_pos[i] = static_cast<std::uint32_t>(live);
    search.order[live++] = i;
  }
  search.order.resize(live);
}

void Solver::refresh_nearest(std::uint32_t i) {
  float d = kInf;
  for (const Search& search : searches_) {
    if (i < search.dist.size()) d = std::min(d, search.dist[i]);
  }
  nearest_[i] = d;
}

void Solver::continue_searches(const Cloth& cloth) {
  bool pending = false;
  bool progressed = false;
  for (Search& search : searches_) {
    if (search.heap.empty() && search.open_list.empty()) continue;
    progressed = true;
    pending = !run_search(cloth, search, true, static_cast<std::size_t>(params_.repair_per_step)) || pending;
  }
  // Settled particles change the strain limit's order (their distance to the pins): redo it once done.
  if ((progressed && !pending) || (pending_limit_order_ && !pending)) {
    pending_limit_order_ = false;
    if (limit_order_stale_) order_strain_limit(cloth);
  }
}

void Solver::attach(const Cloth& cloth, Search& search, std::uint32_t i, bool engage) {
  // Kim et al.'s tether holds a particle within its rest distance of the pin, which is tight only while the
  // straight line to the pin lies in the cloth. Behind a cut the geodesic bends around the cut's tip, and a
  // tether as long as the whole path lets the cloth below a slit hang on its few springs at the tip (25 %
  // and more at rest). So the tether follows the cut: it holds the particle within its straight rest
  // distance of the last particle before the path bends (its anchor), which is itself held the same way
  // (applied first), a chain of straight tethers along the geodesic.
  // "Straight" is tested on the grid: Dijkstra over springs measures octile paths, up to 8 % longer than the
  // straight line, so where the path from the anchor is no longer than the octile distance of the two rest
  // coordinates (no cut in the way) the straight rest distance is the geodesic (and the slack of the octile
  // path would let the middle of a wide drape sag by centimetres). Two detours that bend around nothing are
  // allowed on top: a path from or to a particle off the grid (an exact cut's) is up to about twice its
  // distance from the nearest grid point longer than the octile distance; and past a bend a path runs along
  // the cut's lip, whose notches (deleted triangles) or off-grid particles lengthen it by up to about a cell.
  // Without that allowance the notches of a delete cut's lower lip became anchors for the cloth below them
  // and kept it fluttering (64 x 64 slit: 11.7 %, 2e-3 J after 10 s). Not before the first bend: there a
  // straight tether from the pin is tighter than the path around the cut's tip, and a cut flap could not
  // hang open (exact flap at 32 x 32 with one cell allowed: 18 %).
  // Where the path does bend, the new anchor is the last particle before it where a path CAN bend (a cut's
  // tip, a reflex corner of a cut: is_bend_point), not simply the parent: "the parent" made chains of
  // one-cell tethers down a column below a slit's tip (24 links at 64 x 64) and anchored hundreds of
  // particles on light particles of an exact cut's lip; an anchor moved by the piece hanging from it (the
  // tether moves the piece, the piece moves its anchor) kept a slit's lower piece fluttering forever
  // (tachi-sim's out-of-plane jitter: kinetic energy 4e-4 J after 10 s; now 3e-7 J). A path that fails the
  // test with no such particle since the candidate is a detour of the discretisation: the candidate stays.
  float length2 = kInf;
  std::uint32_t anchor = kNone;
  std::uint32_t bends = 0;
  std::uint32_t last_bend = kNone;
  if (search.last_bend.size() < cloth.particle_count()) {
    search.last_bend.resize(cloth.particle_count(), kNone);
    search.bend_checked.resize(cloth.particle_count(), 0);
  }
  const std::uint32_t parent = search.parent[i];
  if (cloth.inverse_mass[i] != 0.0F && std::isfinite(search.dist[i]) && parent != kNone) {
    const bool parent_is_pin = cloth.inverse_mass[parent] == 0.0F;
    const std::uint32_t candidate = parent_is_pin ? parent : search.anchor[parent];
    const bool past_bend = candidate != kNone && cloth.inverse_mass[candidate] != 0.0F;
    const float lip_detour = past_bend ? std::min(cloth.spacing_x(), cloth.spacing_y()) : 0.0F;
    const auto straight_from = [&](std::uint32_t a) {
      return search.dist[i] - search.dist[a] <= octile(cloth, cloth.rest_uv[i], cloth.rest_uv[a]) * (1.0F + 1e-4F) +
                                                   off_grid(cloth, i) + off_grid(cloth, a) + lip_detour + 1e-6F;
    };
    if (candidate == kNone) {
      anchor = parent;
    } else if (straight_from(candidate)) {
      anchor = candidate;  // last_bend stays unknown: found by a walk if a descendant's path bends
    } else {
      const std::uint32_t bend = parent == candidate ? kNoBend : nearest_bend(cloth, search, parent, candidate);
      // None: a detour of the discretisation, the candidate stays. Either way nothing between the anchor and
      // i can bend.
      anchor = bend != kNoBend ? bend : candidate;
      last_bend = kNoBend;
    }
    const float length = cloth.rest_distance(i, anchor);
    length2 = length * length;
    bends = cloth.inverse_mass[anchor] == 0.0F ? 0 : search.bends[anchor] + 1;
  }
  search.anchor[i] = anchor;
  search.last_bend[i] = last_bend;
  search.bend_checked[i] = cloth.topology_version;
  if (bends != search.bends[i]) tether_order_stale_ = true;
  search.bends[i] = bends;
  std::uint32_t& slot = search.attachment[i];
  // Already in engaging_ (a later repair settling it again): listed once, so it tightens at one speed.
  const bool listed = slot != kNone && std::isfinite(attachments_[slot].length2) &&
                      attachments_[slot].reach2 > attachments_[slot].length2;
  if (slot == kNone) {
    if (!std::isfinite(length2)) return;
    slot = static_cast<std::uint32_t>(attachments_.size());
    attachments_.push_back({i, anchor, length2, bends, length2});
    if (bends > 0) tether_order_stale_ = true;
  } else {
    // A disabled tether keeps a valid anchor index (itself): the step reads it before comparing.
    attachments_[slot] = {i, std::isfinite(length2) ? anchor : i, length2, bends, length2};
  }
  // A tether that comes (or changes anchor) after a cut holds the particle where it is and tightens to its
  // length over the next steps (engage_tethers): projected at once, it yanked the cloth below an advancing
  // tip up past the cut, where the blade met it again.
  if (engage && std::isfinite(length2)) {
    const float now2 = (cloth.position[i] - cloth.position[anchor]).squaredNorm();
    if (now2 > length2) {
      attachments_[slot].reach2 = now2;
      if (!listed) engaging_.push_back(slot);
    }
  }
}

void Solver::engage_tethers() {
  // Tightened at a fixed speed, not by a fraction a step: a fraction of a large excess is still a yank.
  constexpr float kTightenMetresPerSecond = 0.5F;
  const float tighten = kTightenMetresPerSecond * params_.dt;
  std::size_t kept = 0;
  for (const std::uint32_t k : engaging_) {
    Attachment& a = attachments_[k];
    if (!(a.reach2 > a.length2) || !std::isfinite(a.length2)) continue;
    const float reach = std::max(std::sqrt(a.length2), std::sqrt(a.reach2) - tighten);
    a.reach2 = reach * reach;
    if (a.reach2 > a.length2) engaging_[kept++] = k;
  }
  engaging_.resize(kept);
}

std::uint32_t Solver::nearest_bend(const Cloth& cloth, Search& search, std::uint32_t from, std::uint32_t anchor) {
  // The nearest particle where the path can bend, from `from` (included) up to `anchor` (excluded). A record
  // is trusted when it names a particle, or says "none" checked since the last topology change: a cut makes
  // new bend points (a tip) without reopening the particles whose paths pass them, so their old "none" may
  // be out of date. What a walk finds is written back on the particles it passed: each is walked through at
  // most once per topology version (walking every branch again cost a 128 x 128 long stroke 50 ms steps).
  std::uint32_t found = kNoBend;
  std::uint32_t p = from;
  for (; p != anchor && p != kNone; p = search.parent[p]) {
    if (is_bend_point(cloth, p)) {
      found = p;
      break;
    }
    const std::uint32_t known = search.last_bend[p];
    if (known != kNone && (known != kNoBend || search.bend_checked[p] == cloth.topology_version)) {
      found = known;
      break;
    }
  }
  for (std::uint32_t q = from; q != p && q != kNone; q = search.parent[q]) {
    search.last_bend[q] = found;
    search.bend_checked[q] = cloth.topology_version;
  }
  return found;
}

void Solver::order_tethers() {
  // A tether is applied after its anchor's own (fewer bends): counting sort by bends, linear in the tethers.
  tether_order_stale_ = false;
  std::uint32_t most = 0;
  for (const Attachment& a : attachments_) most = std::max(most, a.bends);
  if (most == 0) {  // none bends: the attachments' own order is fine
    tether_order_.clear();
    return;
  }
  std::vector<std::uint32_t> start(static_cast<std::size_t>(most) + 2, 0);
  for (const Attachment& a : attachments_) ++start[a.bends + 1];
  for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
  unbent_tethers_ = start[1];
  // Every entry is written below: resized, not cleared first (zeroing 265k entries each step of a stroke).
  tether_order_.resize(attachments_.size());
  for (std::uint32_t k = 0; k < attachments_.size(); ++k) tether_order_[start[attachments_[k].bends]++] = k;
}

void Solver::build_attachments(const Cloth& cloth) {
  attachments_.clear();
  engaging_.clear();
  tether_order_stale_ = true;
  tether_block_end_.clear();
  searches_.clear();
  const std::size_t n = cloth.particle_count();
  nearest_.assign(n, kInf);
  if (cached_pins_.empty()) return;
  // A few pins (corners): every particle is tethered to each of them. Many pins (an edge): Kim et al. tether
  // to the nearest only, but below a cut a particle held through one tip alone swings down around it and
  // tears the cloth between it and a neighbour held through the other tip (a slit at 64 x 64 rested at 15 %,
  // 28 % in exact mode). So each particle gets four tethers, from four groups of pins along the pinned line,
  // whose paths should pass different tips so that the cloth below a slit hangs from both. Four quarters of
  // the line did not do that: the nearest pin of the right quarter still reached the left third of a slit's
  // lower lip round the left tip, so that part hung from one tip only, the lip sagged like a hammock and its
  // springs stayed over the limit (tachi-sim's jittered 0.65 m slit, 64 x 64: grid 10.8 %, exact 12-19 %).
  // The groups are now the two ends of the pinned line, one pin each, and its two halves: a path from the far
  // end reaches all but the few cells of the lip next to the near tip round the far tip, and the halves keep
  // a pin straight above every particle of an uncut cloth, so it drapes as before. Four tethers per particle
  // instead of one: the plain step costs +90 % at 128 x 128 (docs/benchmarks.md).
  constexpr std::size_t kAllPinsUpTo = 4;
  if (cached_pins_.size() <= kAllPinsUpTo) {
    for (const std::uint32_t pin : cached_pins_) searches_.emplace_back().sources = {pin};
  } else {
    std::vector<std::uint32_t> sorted = cached_pins_;
    std::sort(sorted.begin(), sorted.end(), [&](std::uint32_t a, std::uint32_t b) {
      const auto& ua = cloth.rest_uv[a];
      const auto& ub = cloth.rest_uv[b];
      return ua.x() != ub.x() ? ua.x() < ub.x() : ua.y() < ub.y();
    });
    const auto half = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    searches_.emplace_back().sources = {sorted.front()};
    searches_.emplace_back().sources.assign(sorted.begin(), half);
    searches_.emplace_back().sources.assign(half, sorted.end());
    searches_.emplace_back().sources = {sorted.back()};
  }
  const std::size_t particle_room = cloth.position.capacity();
  reserve_touched(attachments_, searches_.size() * particle_room);
  reserve_touched(tether_order_, searches_.size() * particle_room);
  for (Search& search : searches_) {
    reserve_touched(search.dist, particle_room);
    reserve_touched(search.parent, particle_room);
    reserve_touched(search.parent_spring, particle_room);
    reserve_touched(search.order_pos, particle_room);
    reserve_touched(search.order, 2 * particle_room);
    reserve_touched(search.owner, particle_room);
    reserve_touched(search.attachment, particle_room);
    reserve_touched(search.anchor, particle_room);
    reserve_touched(search.bends, particle_room);
    reserve_touched(search.last_bend, particle_room);
    reserve_touched(search.bend_checked, particle_room);
    reserve_touched(search.open, particle_room);
    reserve_touched(search.open_list, particle_room);
    reserve_touched(search.heap, particle_room);
    search.dist.assign(n, kInf);
    search.parent.assign(n, kNone);
    search.parent_spring.assign(n, kNone);
    search.order_pos.assign(n, kNone);
    search.order.clear();
    search.seeded = 0;
    search.owner.assign(n, kNone);
    search.attachment.assign(n, kNone);
    search.anchor.assign(n, kNone);
    search.bends.assign(n, 0);
    search.last_bend.assign(n, kNone);
    search.bend_checked.assign(n, 0);
    search.open.assign(n, 0);
    search.open_list.clear();
    search.open_count = 0;
    search.heap.clear();
    for (const std::uint32_t s : search.sources) {
      search.dist[s] = 0.0F;
      search.owner[s] = s;
      search.heap.emplace_back(0.0F, s);
    }
    const std::size_t block_begin = attachments_.size();
    run_search(cloth, search, false, std::numeric_limits<std::size_t>::max());
    // The group's tethers by particle, not in the order the search settled them: each holds another particle
    // on a pin, so they are independent and the order changes nothing, but a thread can then find the
    // tethers of its range of particles (front_in_bands), and the sweep reads the positions in order.
    std::size_t next = block_begin;
    std::vector<Attachment> by_particle;
    by_particle.reserve(attachments_.size() - block_begin);
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint32_t& slot = search.attachment[i];
      if (slot == kNone) continue;
      by_particle.push_back(attachments_[slot]);
      slot = static_cast<std::uint32_t>(next++);
    }
    std::copy(by_particle.begin(), by_particle.end(), attachments_.begin() + static_cast<std::ptrdiff_t>(block_begin));
    tether_block_end_.push_back(attachments_.size());
    for (std::uint32_t i = 0; i < n; ++i) nearest_[i] = std::min(nearest_[i], search.dist[i]);
  }
}

bool Solver::parent_spring_intact(const Cloth& cloth, Search& search, std::uint32_t i) {
  const std::uint32_t p = search.parent[i];
  const std::uint32_t k = search.parent_spring[i];
  if (k < cloth.spring_count() && cloth.alive[k] != 0 &&
      ((cloth.spring_a[k] == i && cloth.spring_b[k] == p) || (cloth.spring_a[k] == p && cloth.spring_b[k] == i))) {
    return true;
  }
  // The cut may have re-made the spring under another index (its particles' springs re-derived).
  for (const std::uint32_t other : cloth.springs_of(i)) {
    if (cloth.kind[other] == SpringKind::Bend) continue;
    if ((cloth.spring_a[other] == i && cloth.spring_b[other] == p) || (cloth.spring_a[other] == p && cloth.spring_b[other] == i)) {
      search.parent_spring[i] = other;
      return true;
    }
  }
  return false;
}

void Solver::open_particle(Search& search, std::uint32_t i) {
  // Off its shortest-path tree until the repair settles it again. Its tether stays as it was meanwhile (the
  // cut only lengthened its path, so the old tether is no looser than the new one will be; it was met where
  // the particle is now): turned off, the region below a stroke advancing into a 256 x 256 cloth hung without
  // tethers for the whole stroke and fell stretched (9771 springs over 10 %, now none). A particle the cut
  // separated from a pin group loses that group's tether at once (release_cut_off), or, unreached, when the
  // repair ends (run_search).
  search.dist[i] = kInf;
  search.parent[i] = kNone;
  search.parent_spring[i] = kNone;
  search.owner[i] = kNone;
  search.order_pos[i] = kNone;  // its entry in the order goes stale
  if (search.open[i] == 0) {
    search.open_list.push_back(i);
    ++search.open_count;
  }
  search.open[i] = 1;
  search.anchor[i] = kNone;
  if (search.bends[i] != 0) tether_order_stale_ = true;
  search.bends[i] = 0;
  // Once per particle, however many searches open it: its nearest pin is looked up again after all of them.
  if (opened_mark_[i] == 0) {
    opened_mark_[i] = 1;
    opened_.push_back(i);
  }
}

void Solver::compact_open_list(Search& search) {
  // A repair that a long stroke keeps re-opening never ends, so its list was never cleared: the particles
  // that settled again stayed in it (880k entries for 66k particles by the end of a 256 x 256 stroke), and
  // every cut read them all, as did the repair's seeding (against its budget). Past twice the open ones they
  // are dropped, the rest keeping their order; `seeded` still counts the same particles.
  if (search.open_list.size() <= 2 * search.open_count + 64) return;
  std::size_t kept = 0;
  std::size_t seeded = 0;
  for (std::size_t k = 0; k < search.open_list.size(); ++k) {
    const std::uint32_t i = search.open_list[k];
    if (search.open[i] == 0) continue;
    if (k < search.seeded) ++seeded;
    search.open_list[kept++] = i;
  }
  search.open_list.resize(kept);
  search.seeded = seeded;
}

void Solver::update_attachments(const Cloth& cloth, const std::vector<std::uint32_t>& touched) {
  const std::size_t n = cloth.particle_count();
  nearest_.resize(n, kInf);
  if (searches_.empty()) return;
  // Decremental shortest paths (Ramalingam and Reps 1996): a particle is affected when the spring to its
  // parent on the shortest-path tree is gone, or it is new; so is everything below it on the tree. They are
  // opened here (distance off, old tether kept); the repair that searches them again from the distances of their
  // settled neighbours runs within each step's budget (continue_searches).
  // A cut may also make a path shorter (an exact cut's new triangles' edges cut across a cell): that is not
  // searched for, so a repaired distance may exceed a full build's by a few per cent (up to 10 % after a
  // dozen random strokes on a 24 x 24 cloth, solver_test), never fall short of it. Searching for it too
  // (re-opening a settled particle that a newly settled one reaches by a shorter way) was tried: the 64 x 64
  // exact slit of tachi-sim's CutCli test then rested at 14.9 % strain instead of <= 10 %, likely because
  // attach()'s straightness test, tuned on grid paths, then lets more chains of tethers count as straight
  // around a cut's tip.
  // The subtrees are found in one pass over the settle order from the first orphan: a particle there comes
  // after its parent, so it is opened when its parent was. That is a load and a test per particle, where
  // walking the subtrees through the springs cost ~500 instructions per particle and search (5 ms for the
  // lower half of a 128 x 128 cloth over four searches).
  opened_.clear();
  opened_mark_.resize(n, 0);
  for (Search& search : searches_) {
    const std::size_t old_n = search.dist.size();
    search.dist.resize(n, kInf);
    search.parent.resize(n, kNone);
    search.parent_spring.resize(n, kNone);
    search.owner.resize(n, kNone);
    search.attachment.resize(n, kNone);
    search.anchor.resize(n, kNone);
    search.bends.resize(n, 0);
    search.open.resize(n, 0);
    search.order_pos.resize(n, kNone);
    compact_order(search, n);
    compact_open_list(search);
    const std::size_t open_before = search.open_list.size();
    std::uint32_t first = kNone;
    for (const std::uint32_t i : touched) {
      if (i >= old_n) {
        if (search.open[i] == 0) open_particle(search, i);
        continue;
      }
      if (search.open[i] != 0 || search.parent[i] == kNone || parent_spring_intact(cloth, search, i)) continue;
      first = std::min(first, search.order_pos[i]);
      open_particle(search, i);
    }
    for (std::size_t pos = first == kNone ? search.order.size() : first + 1; pos < search.order.size(); ++pos) {
      const std::uint32_t i = search.order[pos];
      if (search.order_pos[i] != pos) continue;  // stale: it settled again later
      const std::uint32_t p = search.parent[i];
      if (p != kNone && search.open[p] != 0) open_particle(search, i);
    }
    // A repair in progress: a particle still open holds a tentative distance through a settled particle
    // (seeds and relaxations always come from one). If this cut opened that particle or cut the spring to
    // it, the distance is gone with it, so it is forgotten and the particle seeded again (only it: seeding
    // the whole open region again on every cut of a long stroke cost a 256 x 256 step 40 ms).
    for (std::size_t k = 0; k < open_before; ++k) {
      const std::uint32_t i = search.open_list[k];
      const std::uint32_t p = search.parent[i];
      if (p == kNone || (search.open[p] == 0 && parent_spring_intact(cloth, search, i))) continue;
      search.dist[i] = kInf;
      search.parent[i] = kNone;
      search.parent_spring[i] = kNone;
      search.owner[i] = kNone;
      if (k < search.seeded) seed(cloth, search, i);  // else the repair's seeding reaches it
    }
  }
  for (const std::uint32_t i : opened_) {
    refresh_nearest(i);
    opened_mark_[i] = 0;
  }
}

void Solver::drop_tether(const Search& search, std::uint32_t i) {
  if (search.attachment[i] != kNone) attachments_[search.attachment[i]] = {i, i, kInf, 0, kInf};
}

void Solver::release(Search& search, std::uint32_t i) {
  // No settled particle of the group can reach it: its tether goes, and the repair has nothing to look for.
  // Closed now rather than when the repair ends (run_search), the repair does not seed it: seeding the
  // 8k particles of a 128 x 128 cloth's cut-off half, in each of four groups, was ~1 ms of the step after
  // the cut. Its distance is already off (open_particle; a tentative one through a cut spring was reset).
  drop_tether(search, i);
  search.open[i] = 0;
  --search.open_count;
  search.dist[i] = kInf;
  search.parent[i] = kNone;
  search.parent_spring[i] = kNone;
  search.owner[i] = kNone;
}

std::uint32_t Solver::open_groups(std::uint32_t i) const {
  std::uint32_t bits = 0;
  for (std::size_t s = 0; s < searches_.size(); ++s) {
    if (searches_[s].open[i] != 0) bits |= 1U << s;
  }
  return bits;
}

std::uint32_t Solver::settled_groups(std::uint32_t i) const {
  std::uint32_t bits = 0;
  for (std::size_t s = 0; s < searches_.size(); ++s) {
    const Search& search = searches_[s];
    if (settled(search.open[i], search.dist[i])) bits |= 1U << s;
  }
  return bits;
}

void Solver::release_cut_off(const Cloth& cloth, const std::vector<std::uint32_t>& touched) {
  // An open particle keeps its old tether until the repair settles it again (open_particle), which is right
  // while it still hangs from the pins: the cut only lengthened its path, so the old tether holds it no
  // farther from its anchor than it already is. A particle the cut has separated from a pin group has no new
  // path at all, and its old tether would hold a cut-off piece in the air until the repair had settled
  // everything else. So after each cut the open particles the cut touched are flooded through live springs,
  // collecting the pin groups (a bit per search) whose settled particles they meet; a component of open
  // particles that meets no settled particle of a group loses that group's tethers now and leaves its repair
  // (release).
  // A piece the cut separated lies along the cut, so it contains a touched particle. The flood of a
  // component stops as soon as it has met every group: from a particle next to the advancing tip of a stroke
  // that is a few cells (the tip is next to uncut cloth); a flood that reaches a particle an earlier flood
  // visited stops too (same component). Only a component that is really cut off is flooded whole. Flooding
  // every open particle after every cut cost a 256 x 256 long stroke's cutting steps ~2 ms each.
  const std::size_t n = cloth.particle_count();
  flood_seen_.resize(n, 0);
  const std::uint32_t all = (1U << searches_.size()) - 1U;
  const auto is_open = [&](std::uint32_t i) { return open_groups(i) != 0; };
  flood_visited_.clear();
  // Past this many particles the floods stop and the components are labelled by union-find over all springs
  // instead, in spring order: a cut-off piece is flooded whole, and hopping through the springs of 36k
  // particles of a 256 x 256 piece cost 6.9 ms where two passes over the spring arrays cost ~1.5 ms.
  const std::size_t flood_cap = std::max<std::size_t>(1024, n / 16);
  for (const std::uint32_t start : touched) {
    if (flood_visited_.size() > flood_cap) break;
    if (start >= n || flood_seen_[start] != 0 || !is_open(start)) continue;
    const std::size_t component = flood_visited_.size();
    flood_seen_[start] = 1;
    flood_visited_.push_back(start);
    std::uint32_t met = 0;
    bool joined = false;  // reached a particle an earlier flood visited: that component's verdict stands
    for (std::size_t q = component; q < flood_visited_.size() && met != all && !joined && q <= flood_cap; ++q) {
      const std::uint32_t i = flood_visited_[q];
      met |= settled_groups(i);  // open in some searches only: settled in the others
      for (const std::uint32_t k : cloth.springs_of(i)) {
        if (cloth.kind[k] == SpringKind::Bend) continue;
        const std::uint32_t j = cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
        met |= settled_groups(j);
        if (flood_seen_[j] != 0) {
          if (flood_seen_[j] == 2) joined = true;
          continue;
        }
        if (!is_open(j)) continue;
        flood_seen_[j] = 1;
        flood_visited_.push_back(j);
      }
    }
    if (flood_visited_.size() > flood_cap) break;  // unfinished: the components are labelled instead
    if (met != all && !joined) {
      // Flooded whole: every group it never met has no path to it.
      for (std::size_t q = component; q < flood_visited_.size(); ++q) {
        const std::uint32_t i = flood_visited_[q];
        for (std::size_t s = 0; s < searches_.size(); ++s) {
          if ((met & (1U << s)) == 0 && searches_[s].open[i] != 0) release(searches_[s], i);
        }
      }
    }
    for (std::size_t q = component; q < flood_visited_.size(); ++q) flood_seen_[flood_visited_[q]] = 2;
  }
  for (const std::uint32_t i : flood_visited_) flood_seen_[i] = 0;
  if (flood_visited_.size() > flood_cap) release_cut_off_by_components(cloth);
}

void Solver::release_cut_off_by_components(const Cloth& cloth) {
  // release_cut_off's verdict for every open particle at once: the components of the open particles through
  // live springs (union-find, Tarjan 1975, over the spring arrays in order), each with the pin groups whose
  // settled particles it touches.
  const std::size_t n = cloth.particle_count();
  const std::uint32_t all = (1U << searches_.size()) - 1U;
  // open_groups and settled_groups of every particle, computed a search at a time (loops the compiler
  // vectorises: called per particle they were a quarter of this labelling at 256 x 256).
  flood_open_.assign(n, 0);
  flood_settled_.assign(n, 0);
  for (std::size_t s = 0; s < searches_.size(); ++s) {
    const auto bit = static_cast<std::uint8_t>(1U << s);
    const std::uint8_t* open = searches_[s].open.data();
    const float* dist = searches_[s].dist.data();
    std::uint8_t* open_bits = flood_open_.data();
    std::uint8_t* settled_bits = flood_settled_.data();
    for (std::size_t i = 0; i < n; ++i) {
      open_bits[i] |= open[i] != 0 ? bit : std::uint8_t{0};
      settled_bits[i] |= settled(open[i], dist[i]) ? bit : std::uint8_t{0};
    }
  }
  auto& parent = flood_parent_;
  parent.resize(n);
  std::iota(parent.begin(), parent.end(), 0U);
  const auto find = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  // What each component meets: its own particles' settled groups and those of the settled particles next to
  // it. A spring from an open particle to one that is not gives the open one its neighbour's bits now (in a
  // copy: flood_settled_ is read as it was), and they are folded into the roots once the components are known.
  auto& met = flood_met_;
  met = flood_settled_;
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] == SpringKind::Bend) continue;
    const std::uint32_t a = cloth.spring_a[k];
    const std::uint32_t b = cloth.spring_b[k];
    const bool a_open = flood_open_[a] != 0;
    const bool b_open = flood_open_[b] != 0;
    if (a_open && b_open) {
      const std::uint32_t ra = find(a);
      const std::uint32_t rb = find(b);
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
    } else if (a_open) {
      met[a] |= flood_settled_[b];
    } else if (b_open) {
      met[b] |= flood_settled_[a];
    }
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    if (flood_open_[i] != 0 && parent[i] != i) met[find(i)] |= met[i];
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    if (flood_open_[i] == 0) continue;
    const std::uint32_t missing = all & ~met[find(i)] & flood_open_[i];
    for (std::size_t s = 0; s < searches_.size(); ++s) {
      if ((missing & (1U << s)) != 0) release(searches_[s], i);
    }
  }
}

void Solver::step(Cloth& cloth, const Colliders& colliders) {
  refresh_caches(cloth);
  continue_searches(cloth);
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
  if (params_.threads > 1 && banded()) return;  // the last sub-step wrote the positions back (substep)
  for_chunks(n, params_.threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) cloth.position[i] = work_[i + 1].head<3>();
  });
}

namespace {

using Vec4 = Eigen::Vector4f;
const Vec4 kXyz{1.0F, 1.0F, 1.0F, 0.0F};

enum class Length { Exact, NearRest };

/// Projection of one distance constraint C = |xa - xb| - target (Mueller et al. 2007, eq. 10-11), scaled
/// by the XPBD factor 1 / (wa + wb + alpha~) (Macklin et al. 2016, eq. 18 with lambda = 0).
/// Length::NearRest replaces |d| by its first-order expansion around the target, |d| ~ (|d|^2 + L^2) / 2L
/// (Jakobsen 2001, "Advanced Character Physics"): no square root, the same fixed point |d| = L, and a
/// correction that stays bounded (< |d|) however far the spring is compressed or stretched.
template <Length kLength>
inline void project_distance(Vec4& pa, Vec4& pb, float target, float alpha) {
  const float wa = pa.w(), wb = pb.w();
  const float wsum = wa + wb;
  if (wsum == 0.0F) return;
  const Vec4 d = (pb - pa).cwiseProduct(kXyz);
  const float len2 = d.squaredNorm();
  float c = 0.0F;
  if constexpr (kLength == Length::Exact) {
    if (len2 < 1e-18F) return;  // coincident particles: no direction to correct along
    const float len = std::sqrt(len2);
    c = (len - target) / (len * (wsum + alpha));
  } else {
    const float target2 = target * target;
    c = (len2 - target2) / ((len2 + target2) * (wsum + alpha));
  }
  pa += (wa * c) * d;
  pb -= (wb * c) * d;
}

/// project_distance<Length::NearRest> on four independent springs at once (SSE, x86-64 baseline):
/// the same arithmetic per lane, so the sweep is still Gauss-Seidel in the same fixed order.
void sweep_near_rest(Vec4* x, const Solver::Group* first, const Solver::Group* last, float alpha) {
  const __m128 alpha4 = _mm_set1_ps(alpha);
  const __m128 zero = _mm_setzero_ps();
  for (const Solver::Group* it = first; it != last; ++it) {
    const Solver::Group& g = *it;
    __m128 a0 = _mm_load_ps(x[g.a[0]].data()), a1 = _mm_load_ps(x[g.a[1]].data());
    __m128 a2 = _mm_load_ps(x[g.a[2]].data()), a3 = _mm_load_ps(x[g.a[3]].data());
    __m128 b0 = _mm_load_ps(x[g.b[0]].data()), b1 = _mm_load_ps(x[g.b[1]].data());
    __m128 b2 = _mm_load_ps(x[g.b[2]].data()), b3 = _mm_load_ps(x[g.b[3]].data());
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);  // a0 = x of the four a's, a1 = y, a2 = z, a3 = inverse mass
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    const __m128 dx = _mm_sub_ps(b0, a0), dy = _mm_sub_ps(b1, a1), dz = _mm_sub_ps(b2, a2);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 rest2 = _mm_load_ps(g.rest2);
    const __m128 wsum = _mm_add_ps(a3, b3);
    const __m128 denominator = _mm_mul_ps(_mm_add_ps(len2, rest2), _mm_add_ps(wsum, alpha4));
    // Both ends fixed (wsum = 0, alpha = 0) would divide by zero: such lanes get c = 0.
    const __m128 c = _mm_and_ps(_mm_div_ps(_mm_sub_ps(len2, rest2), denominator), _mm_cmpgt_ps(wsum, zero));
    const __m128 ca = _mm_mul_ps(a3, c), cb = _mm_mul_ps(b3, c);
    a0 = _mm_add_ps(a0, _mm_mul_ps(ca, dx));
    a1 = _mm_add_ps(a1, _mm_mul_ps(ca, dy));
    a2 = _mm_add_ps(a2, _mm_mul_ps(ca, dz));
    b0 = _mm_sub_ps(b0, _mm_mul_ps(cb, dx));
    b1 = _mm_sub_ps(b1, _mm_mul_ps(cb, dy));
    b2 = _mm_sub_ps(b2, _mm_mul_ps(cb, dz));
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    _mm_store_ps(x[g.a[0]].data(), a0);
    _mm_store_ps(x[g.a[1]].data(), a1);
    _mm_store_ps(x[g.a[2]].data(), a2);
    _mm_store_ps(x[g.a[3]].data(), a3);
    _mm_store_ps(x[g.b[0]].data(), b0);
    _mm_store_ps(x[g.b[1]].data(), b1);
    _mm_store_ps(x[g.b[2]].data(), b2);
    _mm_store_ps(x[g.b[3]].data(), b3);
  }
}

/// One tether (step 2): the particle is brought back onto the sphere of its reach around the anchor.
template <typename Tether>
inline void apply_tether(Vec4* x, const Tether& a) {
  Vec4& p = x[a.particle];
  if (p.w() == 0.0F) return;
  const Vec4& anchor = x[a.anchor];
  const Vec4 d = (p - anchor).cwiseProduct(kXyz);
  const float len2 = d.squaredNorm();
  if (len2 > a.reach2) p.head<3>() = anchor.head<3>() + d.head<3>() * std::sqrt(a.reach2 / len2);
}

/// apply_tether on four tethers at once (SSE, x86-64 baseline), in order: the same arithmetic per lane
/// (|d|^2 summed as Eigen sums a 4-vector, (x^2 + z^2) + y^2), so the same positions bit for bit. Four whose
/// particles or anchors overlap (one's particle is another's particle or anchor: behind a cut an anchor is a
/// particle with tethers of its own) go one by one. Most tethers are slack: a quad none of which is taut is
/// only read. `at(k)` is the k-th tether in the order they are applied.
template <typename At>
void sweep_tethers(Vec4* x, std::size_t count, const At& at) {
  std::size_t k = 0;
  for (; k + 4 <= count; k += 4) {
    const auto& t0 = at(k);
    const auto& t1 = at(k + 1);
    const auto& t2 = at(k + 2);
    const auto& t3 = at(k + 3);
    const __m128i particles = _mm_setr_epi32(static_cast<int>(t0.particle), static_cast<int>(t1.particle),
                                             static_cast<int>(t2.particle), static_cast<int>(t3.particle));
    const __m128i anchors = _mm_setr_epi32(static_cast<int>(t0.anchor), static_cast<int>(t1.anchor),
                                           static_cast<int>(t2.anchor), static_cast<int>(t3.anchor));
    // Every pair of lanes (i != j): particle i against particle j, particle i against anchor j.
    const __m128i p1 = _mm_shuffle_epi32(particles, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128i p2 = _mm_shuffle_epi32(particles, _MM_SHUFFLE(1, 0, 3, 2));
    const __m128i a1 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128i a2 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(1, 0, 3, 2));
    const __m128i a3 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(2, 1, 0, 3));
    const __m128i overlap = _mm_or_si128(
        _mm_or_si128(_mm_cmpeq_epi32(particles, p1), _mm_cmpeq_epi32(particles, p2)),
        _mm_or_si128(_mm_cmpeq_epi32(particles, a1),
                     _mm_or_si128(_mm_cmpeq_epi32(particles, a2), _mm_cmpeq_epi32(particles, a3))));
    if (_mm_movemask_epi8(overlap) != 0) {
      apply_tether(x, t0);
      apply_tether(x, t1);
      apply_tether(x, t2);
      apply_tether(x, t3);
      continue;
    }
    __m128 px = _mm_load_ps(x[t0.particle].data()), py = _mm_load_ps(x[t1.particle].data());
    __m128 pz = _mm_load_ps(x[t2.particle].data()), pw = _mm_load_ps(x[t3.particle].data());
    __m128 ax = _mm_load_ps(x[t0.anchor].data()), ay = _mm_load_ps(x[t1.anchor].data());
    __m128 az = _mm_load_ps(x[t2.anchor].data()), aw = _mm_load_ps(x[t3.anchor].data());
    _MM_TRANSPOSE4_PS(px, py, pz, pw);  // px = x of the four particles, ..., pw = inverse mass
    _MM_TRANSPOSE4_PS(ax, ay, az, aw);
    const __m128 dx = _mm_sub_ps(px, ax), dy = _mm_sub_ps(py, ay), dz = _mm_sub_ps(pz, az);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dz, dz)), _mm_mul_ps(dy, dy));
    const __m128 reach2 = _mm_setr_ps(t0.reach2, t1.reach2, t2.reach2, t3.reach2);
    const __m128 taut = _mm_and_ps(_mm_cmpgt_ps(len2, reach2), _mm_cmpneq_ps(pw, _mm_setzero_ps()));
    if (_mm_movemask_ps(taut) == 0) continue;
    const __m128 scale = _mm_sqrt_ps(_mm_div_ps(reach2, len2));
    const auto pick = [&](__m128 moved, __m128 kept) {
      return _mm_or_ps(_mm_and_ps(taut, moved), _mm_andnot_ps(taut, kept));
    };
    px = pick(_mm_add_ps(ax, _mm_mul_ps(dx, scale)), px);
    py = pick(_mm_add_ps(ay, _mm_mul_ps(dy, scale)), py);
    pz = pick(_mm_add_ps(az, _mm_mul_ps(dz, scale)), pz);
    _MM_TRANSPOSE4_PS(px, py, pz, pw);
    _mm_store_ps(x[t0.particle].data(), px);
    _mm_store_ps(x[t1.particle].data(), py);
    _mm_store_ps(x[t2.particle].data(), pz);
    _mm_store_ps(x[t3.particle].data(), pw);
  }
  for (; k < count; ++k) apply_tether(x, at(k));
}

/// Whether structural spring s is longer than `limit` times its rest length (substep step 5's test; the
/// parallel scan for the first such spring asks the same question with the same arithmetic).
inline bool over_limit(const Vec4* x, const Solver::PackedSpring& s, float limit) {
  const Vec4 d = (x[s.b] - x[s.a]).cwiseProduct(kXyz);
  const float target = limit * s.rest;
  return d.squaredNorm() > target * target;
}

}  // namespace

void Solver::build_bands(const Cloth& cloth) {
  // A spring of row v (its upper end's row, the batches' order) touches rows v .. v + 2 (bend springs two
  // apart; structural and shear v .. v + 1). So bands of at least three rows, every other one swept at once,
  // share no particle: a two-colouring of a partition, where each band itself is still swept in the
  // single-threaded order. What a cut changes in place only blanks lanes (particle 0, which never moves);
  // its new springs go after the bands. The check below reads the particles' rows rather than trusting the
  // rule: after a full build of a cut cloth an exact cut's particles have the row of their nearest grid point.
  // The three families share the bands' rows, so that a band can sweep all of its springs at once.
  banded_ = false;
  for (auto& bounds : bands_) bounds.clear();
  const int threads = params_.threads;
  if (threads <= 1) return;
  const auto row_of = [&](std::uint32_t padded) { return cloth.grid[padded - 1].v; };
  const auto first_row = [&](const Group& g) { return std::min(row_of(g.a[0]), row_of(g.b[0])); };
  int rows = 0;
  for (const auto& groups : groups_) {
    if (!groups.empty()) rows = std::max(rows, first_row(groups.back()) + 1);  // sorted by row (sweep_key)
  }
  const int count = 2 * threads;
  constexpr int kRowsPerBand = 3;
  if (rows < kRowsPerBand * count) return;
  std::vector<std::pair<int, int>> reach(static_cast<std::size_t>(count),
                                         {std::numeric_limits<int>::max(), std::numeric_limits<int>::min()});
  for (std::size_t f = 0; f < 3; ++f) {
    std::vector<std::size_t>& bounds = bands_[f];
    const std::vector<Group>& groups = groups_[f];
    bounds.resize(static_cast<std::size_t>(count) + 1);
    std::size_t at = 0;
    for (int j = 0; j < count; ++j) {
      const int from = rows * j / count;
      while (at < groups.size() && first_row(groups[at]) < from) ++at;
      bounds[static_cast<std::size_t>(j)] = at;
    }
    bounds.back() = groups.size();
    for (std::size_t j = 0; j < reach.size(); ++j) {
      for (std::size_t k = bounds[j]; k < bounds[j + 1]; ++k) {
        for (std::size_t l = 0; l < 4; ++l) {
          for (const std::uint32_t p : {groups[k].a[l], groups[k].b[l]}) {
            if (p == 0) continue;
            reach[j].first = std::min(reach[j].first, row_of(p));
            reach[j].second = std::max(reach[j].second, row_of(p));
          }
        }
      }
    }
  }
  for (std::size_t j = 0; j + 2 < reach.size(); ++j) {
    if (reach[j].second >= reach[j + 2].first) {
      for (auto& bounds : bands_) bounds.clear();
      return;
    }
  }
  banded_ = true;
}

void Solver::sweep_springs(Vec4* padded, std::size_t family, float alpha) const {
  const std::vector<Group>& groups = groups_[family];
  const std::vector<std::size_t>& bounds = bands_[family];
  const Group* g = groups.data();
  if (params_.threads <= 1 || bounds.empty()) {
    sweep_near_rest(padded, g, g + groups.size(), alpha);
    return;
  }
  const int count = static_cast<int>(bounds.size()) - 1;
#pragma omp parallel num_threads(params_.threads)
  for (int parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(static)
    for (int j = parity; j < count; j += 2) {
      sweep_near_rest(padded, g + bounds[static_cast<std::size_t>(j)], g + bounds[static_cast<std::size_t>(j) + 1],
                      alpha);
    }
  }
  sweep_near_rest(padded, g + bounds.back(), g + groups.size(), alpha);  // a cut's springs, in order
}

void Solver::sweep_all_tethers(Vec4* x) const {
  const bool ordered = !tether_order_.empty();
  const std::size_t count = ordered ? tether_order_.size() : attachments_.size();
  const auto plain = [this](std::size_t k) -> const Attachment& { return attachments_[k]; };
  const auto by_bends = [this](std::size_t k) -> const Attachment& { return attachments_[tether_order_[k]]; };
  const auto sweep = [&](std::size_t begin, std::size_t end) {
    const auto shifted = [&](const auto& at) { return [&at, begin](std::size_t k) -> const Attachment& { return at(begin + k); }; };
    if (ordered) {
      sweep_tethers(x, end - begin, shifted(by_bends));
    } else {
      sweep_tethers(x, end - begin, shifted(plain));
    }
  };
  if (params_.threads <= 1 || tether_block_end_.empty()) {
    sweep(0, count);
    return;
  }
  // In a pin group's block each tether holds another particle, and those with no bend are anchored on a pin
  // (inverse mass 0, never moved): a block's tethers are independent, and split into chunks they give what
  // one thread gives. Blocks follow one another (a particle has a tether in each); with bends in use the
  // unbent ones lead tether_order_ in attachment order, so each block is a run there too. What follows the
  // blocks (tethers added by repairs, and those anchored past a bend) goes in order on one thread.
  constexpr std::size_t kMaxBlocks = 8;
  std::array<std::size_t, kMaxBlocks> block_end{};
  const std::size_t blocks = std::min(tether_block_end_.size(), kMaxBlocks);
  for (std::size_t b = 0; b < blocks; ++b) {
    block_end[b] = ordered ? static_cast<std::size_t>(std::lower_bound(tether_order_.begin(),
                                                                       tether_order_.begin() +
                                                                           static_cast<std::ptrdiff_t>(unbent_tethers_),
                                                                       tether_block_end_[b]) -
                                                      tether_order_.begin())
                           : tether_block_end_[b];
  }
  std::size_t begin = 0;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t end = block_end[b];
    for_chunks(end - begin, params_.threads,
               [&](std::size_t first, std::size_t last) { sweep(begin + first, begin + last); });
    begin = end;
  }
  sweep(begin, count);
}

void Solver::mark_word(const Vec4* x, float limit, std::size_t word) {
  std::uint64_t bits = 0;
  const std::size_t first = word * 64;
  const std::size_t last = std::min(first + 64, strain_limit_.size());
  for (std::size_t place = first; place < last; ++place) {
    if (over_limit(x, strain_limit_[place], limit)) bits |= std::uint64_t{1} << (place - first);
  }
  limit_dirty_[word] = bits;
}

void Solver::mark_over_limit(const Vec4* x, float limit) {
  const auto words = static_cast<std::ptrdiff_t>(limit_dirty_.size());
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (std::ptrdiff_t w = 0; w < words; ++w) mark_word(x, limit, static_cast<std::size_t>(w));
}

template <typename LimitSpring>
void Solver::limit_locally(const Cloth& cloth, const LimitSpring& limit_spring) {
  // Provot's sweeps converge like Gauss-Seidel on a chain: a load carried along a long line of springs needs
  // passes in proportion to its length. Below a slit at 128 x 128, the ~30 cells of the lower lip next to
  // each tip hang from that tip alone (every pin group's shortest path passes it), so the piece's weight there
  // turns about the tip and is carried along the lip: the jittered 0.65 m grid slit rested at 14.2 % after the
  // 6 full passes, 10.2 % after 30 and 10.0 % after 100. The passes after the full ones visit only the
  // springs the previous pass corrected and those sharing a particle with them, in the sweep's order: at rest
  // a few hundred springs (9.998 %). Only when the last full pass corrected few springs (a thirty-second of
  // them): where it corrected them everywhere (a piece falling fast; before opened particles kept their
  // tethers, a region waiting for its repair) these passes settled nothing and cost the 256 x 256 long
  // stroke's median step +45 %.
  // The visits are capped at an eighth of a full pass: the lip never quite settles (each correction to
  // 9.5 % pushes a neighbour over 10 %), so the passes run to the cap on every sub-step while it hangs there,
  // and a sixteenth left it at 10.4 % (+15 % on that cloth's step, nothing on a cloth within the limit).
  // Going local as soon as any pass corrects few springs, not only after the sixth, was cheaper still (that
  // slit's step -16 %), but the `curve` recording's two journals of 2026-12-02, replayed, then rested at 86 %
  // and 20.7 % (a flap tangled along the cut) instead of 10.0 %: the full passes are kept.
  std::size_t visits_left = strain_limit_.size() / kLocalLimitVisitsPerPass;
  limit_mark_.resize(strain_limit_.size(), 0);
  for (int pass = 0; pass < kLocalLimitPasses && !limit_active_.empty() && visits_left > 0; ++pass) {
    limit_next_.clear();
    for (const std::uint32_t place : limit_active_) {
      for (const std::uint32_t end : {strain_limit_[place].a, strain_limit_[place].b}) {
        for (const std::uint32_t k : cloth.springs_of(end)) {
          const std::uint32_t near = k < limit_slot_.size() ? limit_slot_[k] : kNone;
          if (near == kNone || limit_mark_[near] != 0) continue;
          limit_mark_[near] = 1;
          limit_next_.push_back(near);
        }
      }
    }
    std::sort(limit_next_.begin(), limit_next_.end());
    limit_active_.clear();
    for (const std::uint32_t place : limit_next_) {
      limit_mark_[place] = 0;
      if (visits_left == 0) continue;
      --visits_left;
      if (limit_spring(strain_limit_[place])) limit_active_.push_back(place);
    }
  }
}

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
  // With no cut's springs to sweep after the bands, the strain limit's first reading (mark_over_limit) joins
  // the region: one wait for the other thread fewer per sub-step.
  bool mark = limit > 0.0F;
  for (std::size_t f = 0; f < 3; ++f) mark = mark && bands_[f].back() == groups_[f].size();
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
            const Group* g = groups_[family].data();
            sweep_near_rest(band_padded, g + bands_[family][static_cast<std::size_t>(j)],
                            g + bands_[family][static_cast<std::size_t>(j) + 1], alpha);
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
  // A cut's springs, appended after the bands: in order, family after family.
  const auto tail = [&](std::size_t family, float alpha) {
    const Group* g = groups_[family].data();
    sweep_near_rest(padded, g + bands_[family].back(), g + groups_[family].size(), alpha);
  };
  if (soft) {
    tail(1, shear_alpha);
    tail(2, bend_alpha);
  }
  for (int it = 0; it < params_.iterations; ++it) tail(0, structural_alpha);
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

  // 5. Provot's deformation constraint: a structural spring longer than (1 + max_strain) L is brought
  // back (Provot 1995, section 4), both ends by their inverse masses, sweeping outwards from the pins.
  // Not "follow the leader" (only the end farther from the pins moves; Mueller et al. 2012): behind a
  // cut "farther" points sideways, towards the middle of the cloth below a slit, and one-sided corrections
  // there pulled the two halves apart every sub-step (a 0.65 m slit at 64 x 64 rested at 470 %, at
  // 128 x 128 it exploded). The weight below a cut is carried by the attachments through its tips (step 2).
  // A violating spring is brought to 95 % of the allowed stretch, not exactly to it: the corrections of
  // its neighbours then push it back towards, not over, the limit (a 256^2 cloth otherwise rests with a
  // few springs at 10.08 %).
  const float corrected = 1.0F + 0.95F * params_.max_strain;
  // A correction can stretch a spring swept earlier, so sweeps repeat until one finds nothing to
  // correct (usually the first: the scan without a square root is cheap) or the budget is spent.
  // The springs shorter than a cell go again at the end of each pass (limit_again_, order_strain_limit).
  const auto limit_spring = [&](const PackedSpring& s) {
    if (!over_limit(x, s, limit)) return false;
    project_distance<Length::Exact>(x[s.a], x[s.b], corrected * s.rest, 0.0F);
    return true;
  };
  // Past the full passes, if the last one corrected few springs, the sweeps go on locally (limit_locally).
  //
  // Only the first pass of a sub-step reads every spring: everything moved before it. A spring whose ends
  // have not moved since its last check is not over the limit (that check found it within, or brought it to
  // 95 % of it), so each later pass reads only the springs a correction moved an end of since their last
  // check (limit_dirty_, a bit per place), and still in the sweep's order: the same
  // corrections in the same order as full passes, a fraction of the reads. While a cut's lip hangs at the
  // limit every pass corrects a few springs, so all six run: at 256 x 256 they were most of the step.
  // A pass that has marked a sixteenth of the springs (a swinging or falling piece corrects up to a third)
  // stops marking, and the next pass reads them all.
  bool clean = false;
  bool full = true;
  // Only the last pass records what it corrected: a pass on a falling piece corrects a third of the springs.
  for (int pass = 0; pass < params_.strain_limit_passes && !clean; ++pass) {
    const bool last = pass + 1 == params_.strain_limit_passes;
    if (last) limit_active_.clear();
    std::size_t corrections = 0;
    bool marking = params_.sparse_strain_limit;
    std::uint32_t cursor = 0;      // the place being swept; marks past it in a full pass need no bit
    std::uint64_t this_word = 0;   // a sparse pass's bits still to sweep in the cursor's word
    std::size_t marked = 0;        // places marked for the next pass
    const auto mark_springs_of = [&](std::uint32_t particle) {
      for (const std::uint32_t k : cloth.springs_of(particle)) {
        const std::uint32_t t = k < limit_slot_.size() ? limit_slot_[k] : kNone;
        if (t == kNone) continue;
        const std::uint64_t bit = std::uint64_t{1} << (t & 63U);
        if (t > cursor) {
          if (full) continue;  // swept later in this pass anyway
          if ((t >> 6U) == (cursor >> 6U)) {
            this_word |= bit;
            continue;
          }
        }
        std::uint64_t& word = limit_dirty_[t >> 6U];
        marked += (word & bit) == 0 ? 1U : 0U;
        word |= bit;
      }
    };
    const auto sweep = [&](std::uint32_t place) {
      const PackedSpring& spring = strain_limit_[place];
      if (!limit_spring(spring)) return;
      ++corrections;
      if (last) limit_active_.push_back(place);
      if (!marking) return;
      if (marked * kSparseLimitShare > places) {
        marking = false;  // the next pass is full; so is the rest of this one (its marks stop here)
        return;
      }
      mark_springs_of(spring.a);
      mark_springs_of(spring.b);
    };
    std::uint32_t place = 0;
    if (full && threads > 1 && marking) {
      // A full pass on several threads: which springs are over the limit now is read on all of them
      // (mark_over_limit), and the pass sweeps those as a sparse pass does, with the springs that its own
      // corrections move an end of. A spring neither over the limit nor moved since would be found within: the
      // same corrections as the full pass (only when marking stops, a sixteenth of the springs marked, can the
      // rest of the pass differ from one thread's, for it counts the marks ahead of the sweep too).
      if (pass > 0 || !premarked) mark_over_limit(x, limit);  // the first pass's: read with the springs
      full = false;
    }
    if (!full) {
      for (std::size_t w = 0; w < limit_dirty_.size() && marking; ++w) {
        this_word = limit_dirty_[w];
        limit_dirty_[w] = 0;
        while (this_word != 0 && marking) {
          place = static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(std::countr_zero(this_word)));
          this_word &= this_word - 1;
          cursor = place;
          sweep(place);
        }
      }
      ++place;  // marking stopped: the rest of the pass is full
    } else {
      std::fill(limit_dirty_.begin(), limit_dirty_.end(), 0);
    }
    if (full || !marking) {
      full = true;
      for (; place < places; ++place) {
        cursor = place;
        sweep(place);
      }
    }
    cursor = static_cast<std::uint32_t>(places);  // marks from here on are for the next pass
    for (const std::uint32_t again : limit_again_) {
      std::uint64_t& word = limit_dirty_[again >> 6U];
      const std::uint64_t bit = std::uint64_t{1} << (again & 63U);
      if (!full && marking && (word & bit) == 0) continue;
      word &= ~bit;
      sweep(again);
    }
    clean = corrections == 0;
    full = !marking;
  }
  // Not clean: every pass ran (validate: strain_limit_passes >= 1), so limit_active_ is this sub-step's last.
  if (!clean && few_limit_corrections()) limit_locally(cloth, limit_spring);

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
