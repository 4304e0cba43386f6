// The pin groups' shortest paths (Dijkstra over live structural and shear springs, search_paths) and their
// repair after a cut: decremental shortest paths (Ramalingam and Reps 1996). The particles whose path the cut
// broke, and their subtrees, are opened (update_attachments, open_particle; they keep their old tethers) and
// searched again from their settled neighbours within a budget per step (continue_repairs). Which particles a
// cut separated from a pin group altogether: tether_release.cpp.
#include "tachi/sim/solver.hpp"

#include "solver_common.hpp"

#include <algorithm>
#include <cmath>

namespace tachi::sim {

using solver_detail::kInf;
using solver_detail::kNone;
using solver_detail::settled;

float Solver::pin_distance(std::size_t index, std::uint32_t particle) const {
  if (index >= pin_groups_.size() || particle >= pin_groups_[index].dist.size()) return kInf;
  const PinGroup& group = pin_groups_[index];
  return group.open[particle] != 0 ? kInf : group.dist[particle];
}

std::size_t Solver::open_particles() const {
  std::size_t open = 0;
  for (const PinGroup& group : pin_groups_) open += group.open_count;
  return open;
}

std::size_t Solver::repair_list_entries() const {
  std::size_t entries = 0;
  for (const PinGroup& group : pin_groups_) entries += group.open_list.size();
  return entries;
}

bool Solver::repairing() const {
  return cut_work_pending() || std::any_of(pin_groups_.begin(), pin_groups_.end(),
                     [](const PinGroup& s) { return !s.heap.empty() || !s.open_list.empty(); });
}

void Solver::seed(const Cloth& cloth, PinGroup& group, std::uint32_t i) {
  // An open particle's distance through its settled neighbours, into the heap (the repair's start).
  for (const std::uint32_t k : cloth.springs_of(i)) {
    if (cloth.kind[k] == SpringKind::Bend) continue;
    const std::uint32_t j = cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
    if (!settled(group.open[j], group.dist[j])) continue;
    const float d = group.dist[j] + cloth.rest_length[k];
    if (d < group.dist[i]) {
      group.dist[i] = d;
      group.parent[i] = j;
      group.parent_spring[i] = k;
      group.owner[i] = group.owner[j];
    }
  }
  if (std::isfinite(group.dist[i])) {
    group.heap.emplace_back(group.dist[i], i);
    std::push_heap(group.heap.begin(), group.heap.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  }
}

bool Solver::search_paths(const Cloth& cloth, PinGroup& group, bool repair, std::size_t& budget) {
  // Dijkstra over live structural and shear springs (rest lengths), at most `budget` particles settled per
  // call. A repair (after a cut) first seeds every open particle with its distance through its settled
  // neighbours (over as many calls as that takes), then relaxes only the open particles: the others'
  // distances are final (a cut only lengthens paths, so a particle whose shortest path the cut did not touch
  // keeps it); each particle it settles gets a tether from its new path (attach; the old one held it meanwhile). Seeding is finished before anything settles, so no particle settles at a
  // distance a seed not yet in the heap would have shortened. Returns true when the search is complete.
  auto& heap = group.heap;
  const auto greater = [](const auto& x, const auto& y) { return x.first > y.first; };
  const auto neighbour = [&](std::uint32_t k, std::uint32_t i) {
    return cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
  };
  if (repair) {
    // Seeding has its own allowance per call, four times the settling budget (a seed costs less than a
    // settle: no heap pops); nothing settles before every open particle is seeded. Counted against the
    // settling budget itself, seeding kept a large opened region unsettled for twice as long, and the cloth
    // swinging under cut_bench's long stroke met it folded (a 128 x 128 grid stroke cut off a third piece).
    std::size_t seeds = 4 * budget;
    while (group.seeded < group.open_list.size() && seeds > 0) {
      const std::uint32_t i = group.open_list[group.seeded++];
      --seeds;
      if (group.open[i] != 0) seed(cloth, group, i);
    }
    if (group.seeded < group.open_list.size()) return false;
  }
  while (!heap.empty() && budget > 0) {
    std::pop_heap(heap.begin(), heap.end(), greater);
    const auto [d, i] = heap.back();
    heap.pop_back();
    if (d != group.dist[i]) continue;  // superseded: a shorter path came, or a later cut reset it
    if (repair) {
      if (group.open[i] == 0) continue;
      group.open[i] = 0;
      --group.open_count;
      if (!group.apart.active) refresh_nearest(i);  // else run_apart does, once every group is in
    }
    group.order_pos[i] = static_cast<std::uint32_t>(group.order.size());
    group.order.push_back(i);
    // In the order particles settle: a particle's anchor comes from its parent's, settled before it.
    if (params_.long_range_attachments) attach(cloth, group, i, repair);
    --budget;
    for (const std::uint32_t k : cloth.springs_of(i)) {
      if (cloth.kind[k] == SpringKind::Bend) continue;
      const std::uint32_t j = neighbour(k, i);
      const float dj = d + cloth.rest_length[k];
      if (repair && group.open[j] == 0) {
        // A settled particle that this one reaches by a shorter way: an exact cut's new springs can make a
        // shortcut (a cut only lengthens paths otherwise). It is opened again and settles at the shorter
        // distance, and so do, through it, the particles below it on its tree. Left as it was, its subtree
        // kept distances up to 25 % too long after random strokes (and so tethers that loose).
        if (!settled(group.open[j], group.dist[j]) || !(dj < group.dist[j] * (1.0F - 1e-6F))) continue;
        reopen_shorter(cloth, group, j);
      } else if (!repair && group.order_pos[j] != kNone) {
        continue;
      }
      if (dj < group.dist[j]) {
        group.dist[j] = dj;
        group.parent[j] = i;
        group.parent_spring[j] = k;
        group.owner[j] = group.owner[i];
        heap.emplace_back(dj, j);
        std::push_heap(heap.begin(), heap.end(), greater);
      }
    }
  }
  if (!heap.empty()) return false;
  // What the repair never reached is cut off from this pin: its tether, kept while it was open, goes.
  for (const std::uint32_t i : group.open_list) {
    if (group.open[i] != 0) release(group, i);
  }
  group.open_list.clear();
  group.seeded = 0;
  return true;
}

void Solver::reopen_shorter(const Cloth& cloth, PinGroup& group, std::uint32_t root) {
  // Opened again during the repair's settling (search_paths), after its seeding, with every particle below
  // it on its tree: their paths all run through it, so they all get shorter. Left settled, those below it
  // kept stale distances, and a later seed through its own child closed a cycle of parents. The whole subtree
  // is opened first, then the particles below the root are seeded from their settled neighbours (none of
  // them in the subtree any more); the root gets its distance from the caller's relaxation. Each is listed
  // as seeded: it has its heap entry now. Their tethers hold them meanwhile, as any open particle's.
  auto& subtree = group.reopen_subtree;
  subtree.assign(1, root);
  for (std::size_t q = 0; q < subtree.size(); ++q) {
    const std::uint32_t i = subtree[q];
    for (const std::uint32_t k : cloth.springs_of(i)) {
      if (cloth.kind[k] == SpringKind::Bend) continue;
      const std::uint32_t c = cloth.spring_a[k] == i ? cloth.spring_b[k] : cloth.spring_a[k];
      if (group.parent[c] == i && settled(group.open[c], group.dist[c])) subtree.push_back(c);
    }
    group.open[i] = 1;
    ++group.open_count;
    group.open_list.push_back(i);
    ++group.seeded;
    group.order_pos[i] = kNone;  // its entry in the order goes stale; appended when it settles again
    group.dist[i] = kInf;
    group.parent[i] = kNone;
    group.parent_spring[i] = kNone;
    group.owner[i] = kNone;
  }
  for (std::size_t q = 1; q < subtree.size(); ++q) seed(cloth, group, subtree[q]);
}

void Solver::compact_order(PinGroup& group, std::size_t particles) {
  // Stale entries (particles that settled again) past half the order: dropped, the live ones keeping their
  // relative order (each still after its parent). Any time, a repair in progress included.
  if (group.order.size() <= 2 * particles) return;
  std::size_t live = 0;
  for (std::size_t pos = 0; pos < group.order.size(); ++pos) {
    const std::uint32_t i = group.order[pos];
    if (group.order_pos[i] != pos) continue;
    group.order_pos[i] = static_cast<std::uint32_t>(live);
    group.order[live++] = i;
  }
  group.order.resize(live);
}

void Solver::refresh_nearest(std::uint32_t i) {
  float d = kInf;
  for (const PinGroup& group : pin_groups_) {
    if (i < group.dist.size()) d = std::min(d, group.dist[i]);
  }
  nearest_[i] = d;
}

template <typename Wanted>
const std::vector<std::size_t>& Solver::groups_where(const Wanted& wanted) {
  // Into a scratch that keeps its room: the repair asks on every step on several threads.
  apart_groups_.clear();
  for (std::size_t g = 0; g < pin_groups_.size(); ++g) {
    if (wanted(pin_groups_[g])) apart_groups_.push_back(g);
  }
  return apart_groups_;
}

template <typename Work>
void Solver::run_apart(const std::vector<std::size_t>& groups, const Work& work) {
  // Each group on one thread, with what would touch the solver's shared state kept in the group (Apart) and
  // applied after, in group order: which thread ran which group cannot change the results. Dynamic
  // scheduling: a group's work is not known in advance (a cut may open one group's whole tree and another's
  // few particles). Nothing to do (the repairs' usual state, every step): no parallel region either.
  if (groups.empty()) return;
  for (const std::size_t g : groups) {
    PinGroup& group = pin_groups_[g];
    group.apart.active = true;
    group.apart.settled_from = group.order.size();
  }
  const auto count = static_cast<int>(groups.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(params_.threads)
  for (int k = 0; k < count; ++k) work(pin_groups_[groups[static_cast<std::size_t>(k)]]);
  for (const std::size_t g : groups) {
    PinGroup& group = pin_groups_[g];
    Apart& apart = group.apart;
    apart.active = false;
    for (const std::uint32_t i : apart.opened) {
      if (opened_mark_[i] != 0) continue;
      opened_mark_[i] = 1;
      opened_.push_back(i);
    }
    engaging_.insert(engaging_.end(), apart.engaging.begin(), apart.engaging.end());
    tether_order_stale_ = tether_order_stale_ || apart.order_stale;
    // Their nearest pin, which the settling updates as it goes on one thread (refresh_nearest reads every
    // group's distance: here, once all of them are in).
    for (std::size_t pos = apart.settled_from; pos < group.order.size(); ++pos) refresh_nearest(group.order[pos]);
    apart.opened.clear();
    apart.engaging.clear();
    apart.order_stale = false;
  }
}

void Solver::continue_repairs(const Cloth& cloth) {
  // One budget for all pin groups (SolverParams::repair_per_step): a cut across a top-pinned cloth opens
  // particles in each of its groups, and a budget per group let the four of a 128 x 128 cloth settle 2673
  // particles in one step. The groups take turns at going first, so a stroke that keeps re-opening the
  // first group does not starve the others.
  std::size_t budget = static_cast<std::size_t>(params_.repair_per_step);
  if (params_.repair_share > 0) budget = std::max(budget, cloth.particle_count() / static_cast<std::size_t>(params_.repair_share));
  bool pending = false;
  bool progressed = false;
  const std::size_t groups = pin_groups_.size();
  const auto repairing_group = [](const PinGroup& g) { return !g.heap.empty() || !g.open_list.empty(); };
  if (params_.threads > 1) {
    // On several threads the groups repair at once (run_apart), each with an even share of the budget.
    const std::vector<std::size_t>& active = groups_where(repairing_group);
    const std::size_t share = std::max<std::size_t>(1, budget / std::max<std::size_t>(1, active.size()));
    run_apart(active, [&](PinGroup& group) {
      std::size_t left = share;
      group.apart.done = search_paths(cloth, group, true, left);
    });
    progressed = !active.empty();
    for (const std::size_t g : active) pending = pending || !pin_groups_[g].apart.done;
  } else {
    for (std::size_t q = 0; q < groups; ++q) {
      PinGroup& group = pin_groups_[(repair_turn_ + q) % groups];
      if (!repairing_group(group)) continue;
      progressed = true;
      pending = budget == 0 || !search_paths(cloth, group, true, budget) || pending;
    }
  }
  if (groups > 0) repair_turn_ = (repair_turn_ + 1) % groups;
  // Settled particles change the strain limit's order (their distance to the pins): redo it once done, on
  // the step after the repair's last (which has paid for its settling: together they were 2x a step).
  if (progressed && !pending) {
    pending_limit_order_ = true;
    return;
  }
  if (pending_limit_order_ && !pending) {
    pending_limit_order_ = false;
    if (limit_order_stale_) order_strain_limit(cloth);
  }
}

bool Solver::parent_spring_intact(const Cloth& cloth, PinGroup& group, std::uint32_t i) {
  const std::uint32_t p = group.parent[i];
  const std::uint32_t k = group.parent_spring[i];
  if (k < cloth.spring_count() && cloth.alive[k] != 0 &&
      ((cloth.spring_a[k] == i && cloth.spring_b[k] == p) || (cloth.spring_a[k] == p && cloth.spring_b[k] == i))) {
    return true;
  }
  // The cut may have re-made the spring under another index (its particles' springs re-derived).
  for (const std::uint32_t other : cloth.springs_of(i)) {
    if (cloth.kind[other] == SpringKind::Bend) continue;
    if ((cloth.spring_a[other] == i && cloth.spring_b[other] == p) || (cloth.spring_a[other] == p && cloth.spring_b[other] == i)) {
      group.parent_spring[i] = other;
      return true;
    }
  }
  return false;
}

void Solver::open_particle(PinGroup& group, std::uint32_t i) {
  // Off its shortest-path tree until the repair settles it again. Its tether stays as it was meanwhile (the
  // cut only lengthened its path, so the old tether is no looser than the new one will be; it was met where
  // the particle is now): turned off, the region below a stroke advancing into a 256 x 256 cloth hung without
  // tethers for the whole stroke and fell stretched (9771 springs over 10 %, now none). A particle the cut
  // separated from a pin group loses that group's tether at once (release_cut_off), or, unreached, when the
  // repair ends (search_paths).
  group.dist[i] = kInf;
  group.parent[i] = kNone;
  group.parent_spring[i] = kNone;
  group.owner[i] = kNone;
  group.order_pos[i] = kNone;  // its entry in the order goes stale
  if (group.open[i] == 0) {
    group.open_list.push_back(i);
    ++group.open_count;
  }
  group.open[i] = 1;
  group.anchor[i] = kNone;
  // group.bends[i] stays what its tether (kept) has, so the tethers' order stays valid: attach compares
  // with it and marks the order stale only if the new tether bends differently. Marking it stale here
  // re-sorted every tether on the step after every cut (0.1-0.17 ms at 128 x 128).
  // Once per particle, however many searches open it: its nearest pin is looked up again after all of them.
  if (group.apart.active) {
    group.apart.opened.push_back(i);  // run_apart lists it once
  } else if (opened_mark_[i] == 0) {
    opened_mark_[i] = 1;
    opened_.push_back(i);
  }
}

void Solver::compact_open_list(PinGroup& group) {
  // A repair that a long stroke keeps re-opening never ends, so its list was never cleared: the particles
  // that settled again stayed in it (880k entries for 66k particles by the end of a 256 x 256 stroke), and
  // every cut read them all, as did the repair's seeding (against its budget). Past twice the open ones they
  // are dropped, the rest keeping their order; `seeded` still counts the same particles.
  if (group.open_list.size() <= 2 * group.open_count + 64) return;
  std::size_t kept = 0;
  std::size_t seeded = 0;
  for (std::size_t k = 0; k < group.open_list.size(); ++k) {
    const std::uint32_t i = group.open_list[k];
    if (group.open[i] == 0) continue;
    if (k < group.seeded) ++seeded;
    group.open_list[kept++] = i;
  }
  group.open_list.resize(kept);
  group.seeded = seeded;
}

void Solver::update_attachments(const Cloth& cloth, const std::vector<std::uint32_t>& touched) {
  const std::size_t n = cloth.particle_count();
  nearest_.resize(n, kInf);
  if (pin_groups_.empty()) return;
  // Decremental shortest paths (Ramalingam and Reps 1996): a particle is affected when the spring to its
  // parent on the shortest-path tree is gone, or it is new; so is everything below it on the tree. They are
  // opened by the cut's work (open_group_subtrees: distance off, old tether kept); the repair that searches
  // them again from the distances of their settled neighbours runs within each step's budget (continue_repairs).
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
  // The pass itself is open_subtrees, which advance_cut_work may spread over the next steps.
  opened_mark_.resize(n, 0);
  for (PinGroup& group : pin_groups_) {
    const std::size_t old_n = group.dist.size();
    group.dist.resize(n, kInf);
    group.parent.resize(n, kNone);
    group.parent_spring.resize(n, kNone);
    group.owner.resize(n, kNone);
    group.attachment.resize(n, kNone);
    group.anchor.resize(n, kNone);
    group.bends.resize(n, 0);
    group.open.resize(n, 0);
    group.order_pos.resize(n, kNone);
    if (group.scan_from == kNoScan) compact_order(group, n);  // not under a pass that is going on
    compact_open_list(group);
    // Which of them the cut orphaned is looked at by the pass (open_group_subtrees), a cut's work that may
    // go on over the next steps: done here, the look at the touched particles was half of the update after
    // cut_bench's 64-segment exact cut at 128 x 128 (0.2 of 0.33 ms on two threads), paid in the cut's step.
    // Until the pass ends the repairs wait and every particle keeps its tether, orphaned or not.
    const auto fresh = std::lower_bound(touched.begin(), touched.end(), static_cast<std::uint32_t>(old_n));
    group.unchecked.insert(group.unchecked.end(), touched.begin(), fresh);
    for (auto it = fresh; it != touched.end(); ++it) {
      const std::uint32_t i = *it;
      group.unchecked.push_back(i | kFreshParticle);
      // On several threads the repairs cannot append tethers (run_apart): the new particle's slot is
      // made now, disabled (as a dropped tether) until the repair settles it.
      if (params_.threads > 1 && group.attachment[i] == kNone) {
        group.attachment[i] = static_cast<std::uint32_t>(attachments_.size());
        attachments_.push_back({i, i, kInf, 0, kInf});
      }
    }
    // With no orphan the pass has no subtree to open, but the repair's tentative distances are still looked
    // at (open_group_subtrees); an orphan found moves its start back.
    if (group.scan_from == kNoScan) group.scan_from = group.order.size();
  }
}

bool Solver::open_group_subtrees(const Cloth& cloth, PinGroup& group, std::size_t& budget) {
  // While this runs the repairs wait (advance_cut_work), so the order does not grow under the pass.
  // Budgeted in particles opened, in 4 touched particles looked at (a few loads from the spring arrays) and
  // in 16 entries passed (a load and a test each, where opening one writes ten arrays): a small cut's pass
  // over most of the order still fits in a step's budget.
  // First the particles the cuts touched (update_attachments): a new one is opened; an old one whose parent
  // spring is gone is an orphan, opened, and the pass over the order starts after it (its subtree follows it
  // there). All of them before the pass goes on, so it meets no orphan it has not opened yet.
  while (group.unchecked_from < group.unchecked.size() && budget > 0) {
    const std::uint32_t entry = group.unchecked[group.unchecked_from++];
    if ((group.unchecked_from & 3U) == 0) --budget;
    const std::uint32_t i = entry & ~kFreshParticle;
    if ((entry & kFreshParticle) != 0) {
      if (group.open[i] == 0) {
        open_particle(group, i);
        budget -= std::min<std::size_t>(budget, 1);
      }
      continue;
    }
    if (group.open[i] != 0 || group.parent[i] == kNone || parent_spring_intact(cloth, group, i)) continue;
    if (group.order_pos[i] != kNone) {
      group.scan_from = std::min(group.scan_from, static_cast<std::size_t>(group.order_pos[i]) + 1);
    }
    open_particle(group, i);
    budget -= std::min<std::size_t>(budget, 1);
  }
  if (group.unchecked_from < group.unchecked.size()) return false;
  group.unchecked.clear();
  group.unchecked_from = 0;
  std::size_t pos = group.scan_from;
  const std::size_t end = group.order.size();
  for (std::size_t passed = 0; pos < end && budget > 0; ++pos) {
    if ((++passed & 15U) == 0) --budget;
    const std::uint32_t i = group.order[pos];
    if (group.order_pos[i] != pos) continue;  // stale: it settled again later
    const std::uint32_t p = group.parent[i];
    if (p != kNone && group.open[p] != 0) {
      open_particle(group, i);
      budget -= std::min<std::size_t>(budget, 1);
    }
  }
  group.scan_from = pos;
  if (pos < end) return false;
  // A repair in progress: a particle still open holds a tentative distance through a settled particle
  // (seeds and relaxations always come from one). If the cuts opened that particle or cut the spring to
  // it, the distance is gone with it, so it is forgotten and the particle seeded again (only it: seeding
  // the whole open region again on every cut of a long stroke cost a 256 x 256 step 40 ms). The particles
  // the cuts opened hold no distance (open_particle), so every entry can be read.
  const std::size_t listed = group.open_list.size();
  for (std::size_t k = 0; k < listed; ++k) {
    const std::uint32_t i = group.open_list[k];
    const std::uint32_t p = group.parent[i];
    if (p == kNone || (group.open[p] == 0 && parent_spring_intact(cloth, group, i))) continue;
    group.dist[i] = kInf;
    group.parent[i] = kNone;
    group.parent_spring[i] = kNone;
    group.owner[i] = kNone;
    if (k < group.seeded) seed(cloth, group, i);  // else the repair's seeding reaches it
  }
  budget -= std::min(budget, listed / 8);
  group.scan_from = kNoScan;
  return true;
}

std::optional<std::size_t> Solver::open_subtrees(const Cloth& cloth, std::size_t budget) {
  bool done = true;
  if (params_.threads > 1) {
    // The groups' passes share nothing but the list of opened particles (kept per group meanwhile: Apart), so
    // on several threads they run at once, each with an even share of the budget. One thread gives the
    // groups the budget in turn instead (the first takes what it needs): each is deterministic for its
    // thread count, as the sweeps are.
    const std::vector<std::size_t>& active = groups_where([](const PinGroup& g) { return g.scan_from != kNoScan; });
    const std::size_t share = std::max<std::size_t>(1, budget / std::max<std::size_t>(1, active.size()));
    std::size_t used = 0;
    run_apart(active, [&](PinGroup& group) {
      std::size_t left = share;
      group.apart.done = open_group_subtrees(cloth, group, left);
      group.apart.used = share - left;
    });
    for (const std::size_t g : active) {
      done = done && pin_groups_[g].apart.done;
      used += pin_groups_[g].apart.used;
    }
    budget -= std::min(budget, used);
  } else {
    for (PinGroup& group : pin_groups_) {
      if (group.scan_from == kNoScan) continue;
      if (!open_group_subtrees(cloth, group, budget)) {
        done = false;
        break;
      }
    }
  }
  if (!done) return std::nullopt;
  for (const std::uint32_t i : opened_) {
    refresh_nearest(i);
    opened_mark_[i] = 0;
  }
  budget -= std::min(budget, opened_.size());
  opened_.clear();
  return budget;
}


}  // namespace tachi::sim
