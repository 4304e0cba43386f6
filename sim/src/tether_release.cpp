// After a cut: the open particles that the cut separated from a pin group lose that group's tether at once
// (release_cut_off): the touched open particles are flooded through live springs, collecting the pin groups
// whose settled particles each component meets; a large cut-off piece is labelled instead by union-find over
// the spring arrays (Tarjan 1975, with the project's one UnionFind, union_find.hpp). Both are phases of a cut's
// tether work (advance_cut_work), which SolverParams::cut_work_per_step spreads over the steps after the cut.
#include "tachi/sim/solver.hpp"

#include "solver_common.hpp"

#include <algorithm>
#include <numeric>

namespace tachi::sim {

using solver_detail::kInf;
using solver_detail::kNone;
using solver_detail::settled;

void Solver::drop_tether(const PinGroup& group, std::uint32_t i) {
  if (group.attachment[i] != kNone) attachments_[group.attachment[i]] = {i, i, kInf, 0, kInf};
}

void Solver::release(PinGroup& group, std::uint32_t i) {
  // No settled particle of the group can reach it: its tether goes, and the repair has nothing to look for.
  // Closed now rather than when the repair ends (search_paths), the repair does not seed it: seeding the
  // 8k particles of a 128 x 128 cloth's cut-off half, in each of four groups, was ~1 ms of the step after
  // the cut. Its distance is already off (open_particle; a tentative one through a cut spring was reset).
  drop_tether(group, i);
  group.bends[i] = 0;  // as its tether now (drop_tether): a tether it gets again is ordered by its own bends
  group.open[i] = 0;
  --group.open_count;
  group.dist[i] = kInf;
  group.parent[i] = kNone;
  group.parent_spring[i] = kNone;
  group.owner[i] = kNone;
}

std::uint32_t Solver::open_groups(std::uint32_t i) const {
  std::uint32_t bits = 0;
  for (std::size_t s = 0; s < pin_groups_.size(); ++s) {
    if (pin_groups_[s].open[i] != 0) bits |= 1U << s;
  }
  return bits;
}

std::uint32_t Solver::settled_groups(std::uint32_t i) const {
  std::uint32_t bits = 0;
  for (std::size_t s = 0; s < pin_groups_.size(); ++s) {
    const PinGroup& group = pin_groups_[s];
    if (settled(group.open[i], group.dist[i])) bits |= 1U << s;
  }
  return bits;
}

bool Solver::release_cut_off(const Cloth& cloth, const std::vector<std::uint32_t>& touched) {
  // An open particle keeps its old tether until the repair settles it again (open_particle), which is right
  // while it still hangs from the pins: the cut only lengthened its path, so the old tether holds it no
  // farther from its anchor than it already is. A particle the cut has separated from a pin group has no new
  // path at all, and its old tether would hold a cut-off piece in the air until the repair had settled
  // everything else. So after each cut the open particles the cut touched are flooded through live springs,
  // collecting the pin groups (a bit each) whose settled particles they meet; a component of open
  // particles that meets no settled particle of a group loses that group's tethers now and leaves its repair
  // (release).
  // A piece the cut separated lies along the cut, so it contains a touched particle. The flood of a
  // component stops as soon as it has met every group: from a particle next to the advancing tip of a stroke
  // that is a few cells (the tip is next to uncut cloth); a flood that reaches a particle an earlier flood
  // visited stops too (same component). Only a component that is really cut off is flooded whole. Flooding
  // every open particle after every cut cost a 256 x 256 long stroke's cutting steps ~2 ms each.
  const std::size_t n = cloth.particle_count();
  flood_seen_.resize(n, 0);
  const std::uint32_t all = (1U << pin_groups_.size()) - 1U;
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
        for (std::size_t s = 0; s < pin_groups_.size(); ++s) {
          if ((met & (1U << s)) == 0 && pin_groups_[s].open[i] != 0) release(pin_groups_[s], i);
        }
      }
    }
    for (std::size_t q = component; q < flood_visited_.size(); ++q) flood_seen_[flood_visited_[q]] = 2;
  }
  for (const std::uint32_t i : flood_visited_) flood_seen_[i] = 0;
  return flood_visited_.size() <= flood_cap;  // else the components are labelled (advance_cut_work)
}

void Solver::clear_cut_work() {
  cut_phase_ = CutPhase::None;
  cut_touched_.clear();
  cut_cursor_ = 0;
  cut_work_steps_ = 0;
  cut_work_fresh_ = false;
  for (PinGroup& group : pin_groups_) {
    group.unchecked.clear();
    group.unchecked_from = 0;
  }
  for (const std::uint32_t i : opened_) opened_mark_[i] = 0;
  opened_.clear();
}

std::size_t Solver::cut_work_left(const Cloth& cloth) const {
  // advance_cut_work's units, phase by phase from the present one on; the floods are counted at their cap.
  const std::size_t n = cloth.particle_count();
  const std::size_t groups = pin_groups_.size();
  const std::size_t springs = cloth.spring_count();
  const std::size_t flood = std::max<std::size_t>(1024, n / 16);
  const std::size_t labelling = n * groups + springs + n;
  switch (cut_phase_) {
    case CutPhase::None:
    case CutPhase::Release:
      return 0;
    case CutPhase::Open: {
      std::size_t left = opened_.size();
      for (const PinGroup& group : pin_groups_) {
        if (group.scan_from == kNoScan) continue;
        left += group.order.size() - std::min(group.scan_from, group.order.size()) + group.open_list.size() / 8;
        left += (group.unchecked.size() - group.unchecked_from) / 2;  // looked at, some opened
      }
      return left + flood + labelling;
    }
    case CutPhase::Flood:
      return flood + labelling;
    case CutPhase::Bits:
      return (n - cut_cursor_) * groups + springs + n;
    case CutPhase::Unite:
      return springs - cut_cursor_ + n;
    case CutPhase::Fold:
      return n - cut_cursor_;
  }
  return 0;
}

bool Solver::advance_cut_work(const Cloth& cloth, std::size_t budget) {
  // The phases in order (CutPhase), each pass going on where the last step left it. Nothing here moves a
  // particle or changes a tether until the release: opened particles keep their old tethers, and the
  // repairs that would give them new ones wait for the work to end (Solver::step).
  const std::size_t n = cloth.particle_count();
  const std::size_t groups = pin_groups_.size();
  const std::uint32_t all = (1U << groups) - 1U;
  const bool to_the_end = budget == static_cast<std::size_t>(-1);
  // A pass over [cursor, size) within the budget: returns the end of this slice.
  const auto slice = [&](std::size_t size, std::size_t cost_each) {
    const std::size_t room = std::max<std::size_t>(1, budget / cost_each);
    const std::size_t end = size - cut_cursor_ <= room ? size : cut_cursor_ + room;
    budget -= std::min(budget, (end - cut_cursor_) * cost_each);
    return end;
  };
  while (cut_phase_ != CutPhase::None && budget > 0) {
    switch (cut_phase_) {
      case CutPhase::None:
        break;
      case CutPhase::Open: {
        const auto left = open_subtrees(cloth, budget);
        if (!left) return false;
        budget = *left;
        cut_phase_ = CutPhase::Flood;
        break;
      }
      case CutPhase::Flood: {
        // release_cut_off's floods, from every particle the cuts touched, stop at a cap: a cut-off piece is
        // flooded whole, so past the cap its components are labelled instead, in the passes below.
        const bool verdicts = release_cut_off(cloth, cut_touched_);
        budget -= std::min(budget, flood_visited_.size());
        if (verdicts) {
          cut_phase_ = CutPhase::None;
          break;
        }
        // release_cut_off's verdict for every open particle at once: the components of the open particles
        // through live springs (union-find, Tarjan 1975, over the spring arrays in order), each with the pin
        // groups whose settled particles it touches.
        flood_open_.assign(n, 0);
        flood_settled_.assign(n, 0);
        flood_sets_.reset(n);
        cut_cursor_ = 0;
        cut_phase_ = CutPhase::Bits;
        break;
      }
      case CutPhase::Bits: {
        // open_groups and settled_groups of every particle, a pin group at a time (loops the compiler
        // vectorises: called per particle they were a quarter of this labelling at 256 x 256).
        const std::size_t from = cut_cursor_;
        const std::size_t to = slice(n, groups);
        for (std::size_t s = 0; s < groups; ++s) {
          const auto bit = static_cast<std::uint8_t>(1U << s);
          const std::uint8_t* open = pin_groups_[s].open.data();
          const float* dist = pin_groups_[s].dist.data();
          std::uint8_t* open_bits = flood_open_.data();
          std::uint8_t* settled_bits = flood_settled_.data();
          for (std::size_t i = from; i < to; ++i) {
            open_bits[i] |= open[i] != 0 ? bit : std::uint8_t{0};
            settled_bits[i] |= settled(open[i], dist[i]) ? bit : std::uint8_t{0};
          }
        }
        cut_cursor_ = to;
        if (to == n) {
          flood_met_ = flood_settled_;
          cut_cursor_ = 0;
          cut_phase_ = CutPhase::Unite;
        }
        break;
      }
      case CutPhase::Unite: {
        // What each component meets: its own particles' settled groups and those of the settled particles
        // next to it. A spring from an open particle to one that is not gives the open one its neighbour's
        // bits now (in a copy: flood_settled_ is read as it was); they are folded into the roots below.
        const std::size_t from = cut_cursor_;
        const std::size_t to = slice(cloth.spring_count(), 1);
        auto& met = flood_met_;
        for (std::size_t k = from; k < to; ++k) {
          if (cloth.alive[k] == 0 || cloth.kind[k] == SpringKind::Bend) continue;
          const std::uint32_t a = cloth.spring_a[k];
          const std::uint32_t b = cloth.spring_b[k];
          const bool a_open = flood_open_[a] != 0;
          const bool b_open = flood_open_[b] != 0;
          if (a_open && b_open) {
            flood_sets_.unite(a, b);
          } else if (a_open) {
            met[a] |= flood_settled_[b];
          } else if (b_open) {
            met[b] |= flood_settled_[a];
          }
        }
        cut_cursor_ = to;
        if (to == cloth.spring_count()) {
          cut_cursor_ = 0;
          cut_phase_ = CutPhase::Fold;
        }
        break;
      }
      case CutPhase::Fold: {
        const std::size_t from = cut_cursor_;
        const std::size_t to = slice(n, 1);
        for (auto i = static_cast<std::uint32_t>(from); i < to; ++i) {
          if (flood_open_[i] == 0) continue;
          if (const std::uint32_t root = flood_sets_.find(i); root != i) flood_met_[root] |= flood_met_[i];
        }
        cut_cursor_ = to;
        if (to == n) {
          cut_phase_ = CutPhase::Release;
          // The release opens the next step, whose budget it is (it is one pass, never sliced).
          if (!to_the_end) return false;
        }
        break;
      }
      case CutPhase::Release: {
        // In one step, however large the piece: released in parts, a piece would fall in parts. Two passes
        // that split over threads (on one thread, half a 128 x 128 cloth's release was 0.57 ms of a 0.6 ms
        // two-thread step): each particle's missing groups (into flood_settled_, read for the last time in
        // Unite), by roots that the Fold pass's finds have made near; then each group's releases, a group
        // on each thread (release writes only its group's arrays and tethers). The same releases as one pass.
        std::uint8_t* missing = flood_settled_.data();
        solver_detail::for_chunks(n, params_.threads, [&](std::size_t begin, std::size_t end) {
          for (std::size_t i = begin; i < end; ++i) {
            missing[i] = flood_open_[i] == 0
                             ? std::uint8_t{0}
                             : static_cast<std::uint8_t>(all & ~flood_met_[flood_sets_.root(static_cast<std::uint32_t>(i))] &
                                                         flood_open_[i]);
          }
        });
        const auto group_count = static_cast<int>(groups);
#pragma omp parallel for schedule(dynamic, 1) num_threads(params_.threads) if (params_.threads > 1)
        for (int g = 0; g < group_count; ++g) {
          const auto bit = static_cast<std::uint8_t>(1U << static_cast<unsigned>(g));
          PinGroup& group = pin_groups_[static_cast<std::size_t>(g)];
          for (std::uint32_t i = 0; i < n; ++i) {
            if ((missing[i] & bit) != 0) release(group, i);
          }
        }
        budget -= std::min(budget, n);
        cut_phase_ = CutPhase::None;
        break;
      }
    }
  }
  if (cut_phase_ != CutPhase::None) return false;
  // The released particles leave the repairs' lists, which the repairs would otherwise read through (two
  // passes over 16k entries a group, 0.6 ms, on the step after the release of half a 128 x 128 cloth).
  // Often nothing is left open at all.
  for (PinGroup& group : pin_groups_) {
    if (group.open_count == 0 && group.heap.empty()) {
      group.open_list.clear();
      group.seeded = 0;
    } else {
      compact_open_list(group);
    }
  }
  clear_cut_work();
  return true;
}

}  // namespace tachi::sim
