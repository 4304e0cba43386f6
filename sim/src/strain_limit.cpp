// Provot's deformation constraint (Provot 1995, sec. 4), sub-step step 5: structural springs longer than
// (1 + max_strain) L are brought back, swept outwards from the pins (order_strain_limit), passes repeated until
// clean or the budget is spent; later passes read only the springs a correction moved (a bit per place), and
// past the full passes a few local ones follow (limit_locally). On several threads the first reading of which
// springs are over the limit is split (mark_over_limit).
#include "tachi/sim/solver.hpp"

#include "constraint_kernels.hpp"
#include "solver_common.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace tachi::sim {

using solver_detail::kNone;
using solver_detail::kXyz;
using solver_detail::Vec4;

using solver_detail::Length;
using solver_detail::project_distance;

namespace {

/// Whether structural spring s is longer than `limit` times its rest length (substep step 5's test; the
/// parallel scan for the first such spring asks the same question with the same arithmetic).
inline bool over_limit(const Vec4* x, const Solver::PackedSpring& s, float limit) {
  const Vec4 d = (x[s.b] - x[s.a]).cwiseProduct(kXyz);
  const float target = limit * s.rest;
  return d.squaredNorm() > target * target;
}

}  // namespace

void Solver::order_strain_limit(const Cloth& cloth) {
  // Outwards from the pins, by the rest distance of the spring's nearer end quantised to half a spacing,
  // ties in spring order (measured in docs/sim.md); pieces no pin holds (+inf) last. Redone after every
  // cut because a cut lengthens the distances behind it: a counting sort, linear in the springs. Each
  // spring's packed form is made in the pass that finds its level, so the scatter reads only the scratch
  // (re-reading the cloth and the distances there made it 0.4 ms at 128 x 128, a third of a step).
  const float unit = 0.5F * std::min(cloth.spacing_x(), cloth.spacing_y());
  auto& level = limit_level_;
  auto& packed = limit_packed_;
  level.clear();
  packed.clear();
  std::uint32_t top = 0;
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0 || cloth.kind[k] != SpringKind::Structural) continue;
    std::uint32_t na = cloth.spring_a[k];
    std::uint32_t nb = cloth.spring_b[k];
    float d = nearest_[na];
    if (nearest_[nb] < d) {
      std::swap(na, nb);
      d = nearest_[na];
    }
    const std::uint32_t l = std::isfinite(d) ? static_cast<std::uint32_t>(d / unit) : kNone;
    if (l != kNone) top = std::max(top, l);
    level.emplace_back(l, k);
    packed.push_back({na, nb, cloth.rest_length[k]});
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
  for (std::size_t e = 0; e < level.size(); ++e) {
    const auto [l, k] = level[e];
    limit_slot_[k] = start[l];
    strain_limit_[start[l]++] = packed[e];
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

void Solver::limit_strain(const Cloth& cloth, Vec4* x, bool premarked) {
  const int threads = params_.threads;
  const float limit = 1.0F + params_.max_strain;
  const std::size_t places = strain_limit_.size();
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
}

}  // namespace tachi::sim
