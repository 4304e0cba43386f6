// The caches a step reads, derived from the cloth's topology (refresh_caches): built in full (full_build)
// when the set of fixed particles changes or the cloth was edited in a way it did not log, else updated from the
// cloth's log of spring edits after a cut (update_incrementally): the cut's lanes blanked, its springs appended,
// the tethers whose shortest paths it broke opened for repair (tether_repair.cpp, tether_release.cpp).
#include "tachi/sim/solver.hpp"

#include "solver_common.hpp"

#include <algorithm>
#include <utility>

namespace tachi::sim {

using solver_detail::kInf;
using solver_detail::kNone;
using solver_detail::mark_index;
using solver_detail::take_marked;

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
  // A cut's springs that its update left loose (loosen_cut_springs) are batched once a step has swept them, or
  // before anything else reads or changes the batches.
  if (!loose_springs_.empty() && (loose_swept_ || !(topology_same && pins_same))) fold_loose_springs(cloth);
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
  clear_cut_work();  // the new pin groups' searches start from scratch
  for (auto& g : quads_) g.clear();
  loose_springs_.clear();  // batched below with every other live spring
  for (auto& bands : loose_bands_) bands.clear();
  banded_ = false;  // the bands are drawn over the new batches (build_bands), not the old ones
  // As much room as the cloth reserved for its cuts (Cloth::reserve): the first cut then grows the solver's
  // per-particle arrays in place instead of reallocating (and faulting in) every one of them at once, which
  // made the step of the first cut at 256 x 256 take ~50 ms.
  const std::size_t particle_room = cloth.position.capacity() + 1;
  reserve_touched(nearest_, particle_room);
  reserve_touched(opened_, particle_room);
  reserve_touched(opened_mark_, particle_room);
  reserve_touched(flood_seen_, particle_room);
  // The labelling of what a cut cut off (advance_cut_work) sizes its scratch to the cloth, and a cut adds particles.
  reserve_touched(flood_open_, particle_room);
  reserve_touched(flood_settled_, particle_room);
  reserve_touched(flood_met_, particle_room);
  flood_sets_.reserve(particle_room);
  reserve_touched(work_, particle_room);
  reserve_touched(old_work_, particle_room);
  reserve_touched(slot_, cloth.spring_a.capacity());
  reserve_touched(limit_slot_, cloth.spring_a.capacity());
  // The update's scratch, as big as the cloth's room: the first cut's update would otherwise allocate them.
  reserve_touched(edited_bits_, cloth.spring_a.capacity() / 64 + 1);
  reserve_touched(edited_bits_apart_, cloth.spring_a.capacity() / 64 + 1);
  reserve_touched(touched_bits_, particle_room / 64 + 1);
  reserve_touched(touched_bits_apart_, particle_room / 64 + 1);
  // As many slots as the cloth's room for springs, not its springs: growing slot_ by a cut's ~4k springs at
  // the update wrote 32 KB that had long left the caches, 0.017 ms of the 64-segment exact cut's update at
  // 128 x 128 on one thread while the other waited. Indexed by spring; its size is not read.
  slot_.assign(std::max(cloth.spring_count(), cloth.spring_a.capacity()), Slot{});
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
  for (auto& g : quads_) {
    lanes_ += 4 * g.size();
    reserve_touched(g, g.size() + g.size() / 4);  // the cuts' springs are appended (compacted past half blanked)
  }
  reserve_touched(strain_limit_, strain_limit_.size() + strain_limit_.size() / 4);
  // And the re-ordering's scratch, which the cut's springs grow past the build's size: allocated (and its
  // pages faulted in) on the step after the repair, it cost that step 0.25 ms at 128 x 128.
  reserve_touched(limit_level_, strain_limit_.capacity());
  reserve_touched(limit_packed_, strain_limit_.capacity());
}

void Solver::update_incrementally(const Cloth& cloth) {
  ++incremental_updates_;
  constexpr std::size_t kAhead = 8;  // springs ahead that the loops over the edits fetch
  std::vector<std::uint32_t>& edited = edited_;
  std::vector<std::uint32_t>& touched = touched_;
  // The springs the cut edited, once each and in increasing order (bit sets: mark_index, take_marked): the
  // edits [from, to) of the cloth's log marked in `bits`, then every mark taken.
  const auto mark_edits = [&](std::size_t from, std::size_t to, std::vector<std::uint64_t>& bits) {
    for (std::size_t e = from; e < to; ++e) mark_index(bits, cloth.spring_edits[e]);
  };
  const auto take_edits = [&] {
    edited.clear();
    take_marked(edited_bits_, edited);
  };
  const auto size_scratch = [&] {
    if (slot_.size() < cloth.spring_count()) slot_.resize(cloth.spring_count(), Slot{});  // past the room
    edited_bits_.resize((cloth.spring_count() + 63) / 64, 0);
    touched_bits_.resize((cloth.particle_count() + 63) / 64, 0);
  };
  // Blanks the lanes of edited springs [from, to) and marks in `bits` the particles they touched, before
  // and after; returns how many lanes it blanked. Each spring has a lane of its own, so two threads may
  // blank two ranges at once.
  const auto blank_edits = [&](std::size_t from, std::size_t to, std::vector<std::uint64_t>& bits) {
    std::size_t blanked = 0;
    const auto touch = [&](std::uint32_t i) { mark_index(bits, i); };
    for (std::size_t e = from; e < to; ++e) {
      // The lanes lie at random places in ~1 MB of batches that the cut's ~2 ms have pushed out of the
      // caches: each spring's slot, and its quad a few springs later, are fetched ahead.
      if (e + 2 * kAhead < to) __builtin_prefetch(&slot_[edited[e + 2 * kAhead]]);
      if (e + kAhead < to) {
        const std::uint32_t ahead = edited[e + kAhead];
        const Slot& t = slot_[ahead];
        if (t.quad != kNone) __builtin_prefetch(&quads_[t.family][t.quad], 1);
        __builtin_prefetch(&cloth.alive[ahead]);
        __builtin_prefetch(&cloth.spring_a[ahead]);
        __builtin_prefetch(&cloth.spring_b[ahead]);
      }
      const std::uint32_t k = edited[e];
      Slot& s = slot_[k];
      if (s.quad != kNone) {
        SpringQuad& g = quads_[s.family][s.quad];
        touch(g.a[s.lane] - 1);
        touch(g.b[s.lane] - 1);
        g.a[s.lane] = 0;  // blanked: both ends on the fixed particle, so the lane does nothing
        g.b[s.lane] = 0;
        g.rest2[s.lane] = 1.0F;
        s = Slot{};
        ++blanked;
      }
      if (cloth.alive[k] != 0) {
        touch(cloth.spring_a[k]);
        touch(cloth.spring_b[k]);
      }
    }
    return blanked;
  };
  // The particles touched, once each and in increasing order: the edited springs' ends and the new particles.
  const auto take_touched = [&] {
    for (std::size_t i = cached_particles_; i < cloth.particle_count(); ++i) {
      mark_index(touched_bits_, static_cast<std::uint32_t>(i));
    }
    touched.clear();
    take_marked(touched_bits_, touched);
  };
  const auto update_tethers = [&] {
    update_attachments(cloth, touched);
    if (!pin_groups_.empty()) {
      // The rest of the tethers' update is a cut's work (advance_cut_work): in this step, or spread over the
      // next ones (SolverParams::cut_work_per_step). A cut that comes meanwhile joins it, and the labelling
      // of what is cut off starts again after the new orphans' subtrees are open.
      const std::size_t before = cut_touched_.size();
      cut_touched_.insert(cut_touched_.end(), touched.begin(), touched.end());
      std::inplace_merge(cut_touched_.begin(), cut_touched_.begin() + static_cast<std::ptrdiff_t>(before),
                         cut_touched_.end());
      cut_touched_.erase(std::unique(cut_touched_.begin(), cut_touched_.end()), cut_touched_.end());
      cut_phase_ = CutPhase::Open;
      cut_cursor_ = 0;
      // As much as cut_work_per_step allows now: a small cut's work ends here, as it always did, and the
      // repairs go on in this step. What is left goes on from the next step.
      const std::size_t now = params_.cut_work_per_step == 0 ? static_cast<std::size_t>(-1)
                                                              : static_cast<std::size_t>(params_.cut_work_per_step);
      cut_work_fresh_ = !advance_cut_work(cloth, now);
    }
  };
  // The strain limit: the cut's springs leave their places (never over the limit: skipped) and its new
  // ones go last, each from its end nearer a pin (nearest_, which update_tethers sizes and may refresh).
  // Re-ordering outwards from the pins (the distances behind a cut grow) is linear in the springs, so it
  // waits for the attachments' repair to settle (continue_repairs) or the next compaction.
  const auto append_to_strain_limit = [&] {
    limit_slot_.resize(cloth.spring_count(), kNone);
    for (std::size_t e = 0; e < edited.size(); ++e) {
      const std::uint32_t k = edited[e];
      // Fetched ahead, as in the blanking: the places are spread over the strain limit's ~0.4 MB.
      if (e + 2 * kAhead < edited.size()) __builtin_prefetch(&limit_slot_[edited[e + 2 * kAhead]]);
      if (e + kAhead < edited.size()) {
        const std::uint32_t ahead = edited[e + kAhead];
        if (limit_slot_[ahead] != kNone) __builtin_prefetch(&strain_limit_[limit_slot_[ahead]], 1);
        __builtin_prefetch(&cloth.kind[ahead]);
        __builtin_prefetch(&cloth.rest_length[ahead]);
      }
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
    // Re-ordered once no repair is going on (continue_repairs): at once if the cut opened nothing.
    pending_limit_order_ = true;
  };
  // The tethers' part and the strain limit's, and the batching of the cut's springs, share no state (pin
  // groups, opened particles, tethers and the strain limit; slots and quads, a family's own) and only read
  // the cloth, so on two threads they run at once: on one thread the update after cut_bench's 64-segment
  // exact cut at 128 x 128 was half of the 0.8 ms median step. The springs' families are batched apart
  // (append_family), each a section of its own after the tethers' part (timed at 0.04-0.10 ms, then
  // 0.03-0.05 for the strain limit's appends; 0.06-0.10 for each family), taken in turn by whichever thread
  // is free: their costs vary from cut to cut, and a fixed pairing left one thread idle for up to 0.07 ms.
  // Before them, reading the edits and blanking their lanes is split in halves, each with a set of marks of
  // its own: the exact cut's 5,233 springs' lanes lie at random places in 1 MB of batches, and that took
  // 0.16 ms on one thread. Every part is an OpenMP section, taken by whichever thread is free: after a
  // large cut the other thread has often gone to sleep (a 64-segment stroke cut at once takes ~2 ms), and
  // the first thread goes on meanwhile. On one thread they run in order, as before; nothing either part
  // does depends on the other, and the marks are the same however they are split, so the results are the
  // same.
  if (params_.threads > 1) {
    // The halves of the blanking: of the springs that have a lane (those before the cut's new ones, in
    // increasing order) and of the new ones, which only mark their particles.
    std::size_t blanked = 0;
    const std::size_t edits = cloth.spring_edits.size();
    const std::size_t edits_middle = edits_read_ + (edits - edits_read_) / 2;
    std::size_t first_new = 0;
    size_scratch();
    edited_bits_apart_.assign(edited_bits_.size(), 0);
    touched_bits_apart_.assign(touched_bits_.size(), 0);
#pragma omp parallel num_threads(2) reduction(+ : blanked)
    {
#pragma omp sections
      {
#pragma omp section
        mark_edits(edits_read_, edits_middle, edited_bits_);
#pragma omp section
        mark_edits(edits_middle, edits, edited_bits_apart_);
      }
#pragma omp single
      {
        for (std::size_t w = 0; w < edited_bits_.size(); ++w) edited_bits_[w] |= edited_bits_apart_[w];
        take_edits();
        first_new = static_cast<std::size_t>(
            std::lower_bound(edited.begin(), edited.end(), static_cast<std::uint32_t>(cached_springs_)) -
            edited.begin());
      }
#pragma omp sections
      {
#pragma omp section
        {
          blanked += blank_edits(0, first_new / 2, touched_bits_);
          blanked += blank_edits(first_new, first_new + (edited.size() - first_new) / 2, touched_bits_);
        }
#pragma omp section
        {
          blanked += blank_edits(first_new / 2, first_new, touched_bits_apart_);
          blanked += blank_edits(first_new + (edited.size() - first_new) / 2, edited.size(), touched_bits_apart_);
        }
      }
#pragma omp single
      {
        for (std::size_t w = 0; w < touched_bits_.size(); ++w) touched_bits_[w] |= touched_bits_apart_[w];
        take_touched();
      }
#pragma omp sections
      {
#pragma omp section
        {
          update_tethers();
          append_to_strain_limit();
        }
        // In bands, the cut's springs are only listed (loosen_cut_springs), swept one by one in this step and
        // batched on the next. Else each family is batched here, the bend springs' (the dearest family,
        // 0.06-0.08 ms after the exact cut) second, beside the tethers' part: listed last, it went to whichever
        // thread freed first, after the tethers' part and the strain limit's 0.07-0.10 ms, while the other
        // thread had finished the two other families.
#pragma omp section
        {
          if (banded_) {
            loosen_cut_springs(cloth, edited);
          } else {
            append_family(cloth, edited, 2);
          }
        }
#pragma omp section
        {
          if (!banded_) append_family(cloth, edited, 0);
        }
#pragma omp section
        {
          if (!banded_) append_family(cloth, edited, 1);
        }
      }
    }
    blanked_ += blanked;
  } else {
    size_scratch();
    mark_edits(edits_read_, cloth.spring_edits.size(), edited_bits_);
    take_edits();
    blanked_ += blank_edits(0, edited.size(), touched_bits_);
    take_touched();
    update_tethers();
    append_springs(cloth, edited);
    append_to_strain_limit();
  }
}

}  // namespace tachi::sim
