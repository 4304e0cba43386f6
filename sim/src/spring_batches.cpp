// The springs' batches: each family (structural, shear, bend) packed four springs that share no particle to a
// quad (SSE lanes), in a fixed sweep order (row by row, colours within a row), the basis of the Gauss-Seidel
// sweeps of sub-step steps 3 and 4 (XPBD, Macklin et al. 2016, eq. 18; Mueller et al. 2007, sec. 3.3). A
// cut's springs are appended (pack_quads). On several threads the quads are split into bands of rows, the
// even bands swept at once and then the odd ones (build_bands, front_in_bands; docs/sim.md "Threads").
#include "tachi/sim/solver.hpp"

#include "constraint_kernels.hpp"
#include "solver_common.hpp"

#include <algorithm>
#include <limits>
#include <utility>

namespace tachi::sim {

using solver_detail::Vec4;

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

}  // namespace

using solver_detail::sweep_near_rest;

namespace {

/// A cut's loose springs (Solver::loosen_cut_springs), one by one in order: project_distance near rest, the
/// arithmetic of a quad's lane (Jakobsen 2001; XPBD, Macklin et al. 2016, eq. 18).
void sweep_loose(Vec4* padded, const std::vector<Solver::PackedSpring>& springs, float alpha) {
  for (const Solver::PackedSpring& sp : springs) {
    solver_detail::project_distance<solver_detail::Length::NearRest>(padded[sp.a], padded[sp.b], sp.rest, alpha);
  }
}

}  // namespace

void Solver::pack_quads(const std::vector<PackedSpring>& springs, const std::vector<std::uint32_t>& keys,
                          std::vector<SpringQuad>& quads) {
  // Four springs of one sweep class (same row and colour) never share a particle on the grid; the check
  // below also keeps that true for springs a cut added or rewired, so the four lanes stay independent.
  SpringQuad g{};
  int lanes = 0;
  std::uint32_t quad_key = 0;
  auto flush = [&] {
    if (lanes == 0) return;
    for (int l = lanes; l < 4; ++l) {
      g.a[l] = 0;  // padding lane: the fixed particle 0 on both ends does nothing
      g.b[l] = 0;
      g.rest2[l] = 1.0F;
    }
    quads.push_back(g);
    lanes = 0;
  };
  for (std::size_t k = 0; k < springs.size(); ++k) {
    const PackedSpring& sp = springs[k];
    const std::uint32_t a = sp.a + 1;
    const std::uint32_t b = sp.b + 1;
    bool clash = lanes > 0 && keys[k] != quad_key;
    for (int l = 0; l < lanes && !clash; ++l) clash = g.a[l] == a || g.a[l] == b || g.b[l] == a || g.b[l] == b;
    if (clash) flush();
    if (lanes == 0) quad_key = keys[k];
    g.a[lanes] = a;
    g.b[lanes] = b;
    g.rest2[lanes] = sp.rest * sp.rest;
    if (++lanes == 4) flush();
  }
  flush();
}

void Solver::append_springs(const Cloth& cloth, const std::vector<std::uint32_t>& springs) {
  for (std::size_t f = 0; f < 3; ++f) append_family(cloth, springs, f);
}

void Solver::append_family(const Cloth& cloth, const std::vector<std::uint32_t>& springs, std::size_t f) {
  // In sweep order: by (sweep key, spring index). The springs come in increasing index (a full build's every
  // live spring, an update's edits read out of a bit set), so a stable counting sort by key gives that order
  // in one pass, where std::sort on packed (key, index) was ~0.1 ms of the update after a 64-segment exact
  // cut at 128 x 128. The keys are the rows times a few colours: their range is small. Springs not in
  // increasing index (no caller passes them so) are sorted as (key, index) pairs instead. Each family has
  // its own scratch and writes only its own quads and its springs' slots, so the update may batch the
  // families on different threads.
  BatchScratch& scratch = batch_scratch_[f];
  std::vector<std::uint32_t>& from = scratch.springs;
  std::vector<std::uint32_t>& from_keys = scratch.keys;
  from.clear();
  from_keys.clear();
  bool increasing = true;
  for (std::size_t j = 0; j < springs.size(); ++j) {
    const std::uint32_t k = springs[j];
    increasing = increasing && (j == 0 || springs[j - 1] < k);
    if (cloth.alive[k] == 0 || static_cast<std::size_t>(cloth.kind[k]) != f) continue;
    from.push_back(k);
    from_keys.push_back(sweep_key(cloth.kind[k], cloth.grid[cloth.spring_a[k]], cloth.grid[cloth.spring_b[k]]));
  }
  std::vector<std::uint32_t>& order = scratch.order;
  std::vector<PackedSpring>& packed = scratch.packed;
  std::vector<std::uint32_t>& keys = scratch.sorted_keys;
  std::vector<SpringQuad>& fresh = scratch.fresh;
  std::vector<std::uint32_t>& count = scratch.count;
  order.resize(from.size());
  keys.resize(from.size());
  if (!from.empty()) {
    const auto [lo, hi] = std::minmax_element(from_keys.begin(), from_keys.end());
    const std::uint32_t low = *lo;
    const std::size_t range = static_cast<std::size_t>(*hi - low) + 1;
    if (increasing && range <= 4 * from.size() + 4096) {
      count.assign(range + 1, 0);
      for (const std::uint32_t key : from_keys) ++count[key - low + 1];
      for (std::size_t c = 1; c <= range; ++c) count[c] += count[c - 1];
      for (std::size_t j = 0; j < from.size(); ++j) {
        const std::uint32_t at = count[from_keys[j] - low]++;
        order[at] = from[j];
        keys[at] = from_keys[j];
      }
    } else {
      // Keys spread too far for a count (a particle's grid row far off), or the springs out of index
      // order: sorted as (key, index) pairs.
      std::vector<std::uint64_t> pairs(from.size());
      for (std::size_t j = 0; j < from.size(); ++j) {
        pairs[j] = (static_cast<std::uint64_t>(from_keys[j]) << 32U) | from[j];
      }
      std::sort(pairs.begin(), pairs.end());
      for (std::size_t j = 0; j < pairs.size(); ++j) {
        order[j] = static_cast<std::uint32_t>(pairs[j] & 0xFFFFFFFFU);
        keys[j] = static_cast<std::uint32_t>(pairs[j] >> 32U);
      }
    }
  }
  packed.clear();
  for (const std::uint32_t k : order) packed.push_back({cloth.spring_a[k], cloth.spring_b[k], cloth.rest_length[k]});
  fresh.clear();
  pack_quads(packed, keys, fresh);
  // Find where each spring landed (pack_quads keeps the order, filling lanes in sequence).
  const auto base = static_cast<std::uint32_t>(quads_[f].size());
  std::size_t next = 0;
  for (std::uint32_t g = 0; g < fresh.size(); ++g) {
    for (std::uint8_t l = 0; l < 4 && next < order.size(); ++l) {
      const std::uint32_t k = order[next];
      if (fresh[g].a[l] != cloth.spring_a[k] + 1 || fresh[g].b[l] != cloth.spring_b[k] + 1) continue;
      slot_[k] = {base + g, l, static_cast<std::uint8_t>(f)};
      ++next;
    }
  }
  quads_[f].insert(quads_[f].end(), fresh.begin(), fresh.end());
  if (banded_) place_cut_quads(cloth, f, base);
}

void Solver::place_cut_quads(const Cloth& cloth, std::size_t family, std::size_t first) {
  // A cut's springs join the band of their rows, swept with it, instead of all going after the bands on
  // one thread: there an exact cut's 1,500 quads at 128 x 128 cost each step after it ~0.07 ms, and kept the
  // strain limit's first reading out of the parallel region (another ~0.07 ms). A quad joins band j only if
  // its particles' rows lie within the rows band j may reach (band_reach_, fixed by build_bands: apart from
  // every other band of j's parity), else it goes after the bands. A cut's particles carry a grid row (a
  // duplicate its original's, an exact cut's vertex its nearest), fixed once made. What is placed depends on
  // the quad alone, not on the other families' quads or the threads, so the families may be placed at once
  // and the positions stay a function of the thread count.
  const std::vector<SpringQuad>& quads = quads_[family];
  std::vector<std::vector<QuadRun>>& runs = band_cut_runs_[family];
  std::vector<QuadRun>& unbanded = unbanded_runs_[family];
  const auto add = [](std::vector<QuadRun>& to, std::size_t q) {
    const auto at = static_cast<std::uint32_t>(q);
    if (!to.empty() && to.back().end == at) {
      ++to.back().end;
    } else {
      to.push_back({at, at + 1});
    }
  };
  for (std::size_t q = first; q < quads.size(); ++q) {
    int low = std::numeric_limits<int>::max();
    int high = std::numeric_limits<int>::min();
    for (std::size_t l = 0; l < 4; ++l) {
      for (const std::uint32_t p : {quads[q].a[l], quads[q].b[l]}) {
        if (p == 0) continue;  // a padding lane
        low = std::min(low, cloth.grid[p - 1].v);
        high = std::max(high, cloth.grid[p - 1].v);
      }
    }
    if (low > high) continue;  // all lanes padding: nothing to sweep
    const std::size_t j = band_of_rows(low, high);
    add(j < band_reach_.size() ? runs[j] : unbanded, q);
  }
}

std::size_t Solver::band_of_rows(int low, int high) const {
  const auto j = static_cast<std::size_t>(std::max<std::ptrdiff_t>(
      0, std::upper_bound(band_first_row_.begin(), band_first_row_.end(), low) - band_first_row_.begin() - 1));
  return low >= band_reach_[j].first && high <= band_reach_[j].second ? j : band_reach_.size();
}

void Solver::loosen_cut_springs(const Cloth& cloth, const std::vector<std::uint32_t>& edited) {
  // Issue 25: on two threads the step of an exact cut at 128 x 128 missed 1.5x the median step, and batching
  // the cut's springs (sorted by sweep key, packed four to a quad, their slots written, the quads placed in
  // bands: 0.06-0.10 ms a family) was on its critical path beside the tethers' part. Here they are only listed,
  // each in the band of its rows by the rule of place_cut_quads (else after the bands), and swept one by one in
  // index order with that band, family by family as the batches are; the next step batches them
  // (fold_loose_springs). Session 35 did this for the bend springs alone (the dearest family); session 37 for
  // every family (docs/benchmarks.md "Threads"). Batching them a step late instead, with no sweep meanwhile,
  // let a sliver corner's cut flip under a 1e-6 m hair and a long stroke's strain grow (session 34b): here
  // they act from the cut's step on, as batched ones would, in another Gauss-Seidel order.
  loose_swept_ = false;
  for (auto& bands : loose_bands_) bands.resize(band_reach_.size() + 1);
  for (const std::uint32_t k : edited) {
    if (cloth.alive[k] == 0) continue;
    loose_springs_.push_back(k);
    const std::uint32_t a = cloth.spring_a[k];
    const std::uint32_t b = cloth.spring_b[k];
    const std::size_t j = band_of_rows(std::min(cloth.grid[a].v, cloth.grid[b].v), std::max(cloth.grid[a].v, cloth.grid[b].v));
    loose_bands_[static_cast<std::size_t>(cloth.kind[k])][j].push_back({a + 1, b + 1, cloth.rest_length[k]});
  }
}

void Solver::fold_loose_springs(const Cloth& cloth) {
  // Batched now as the update would have (append_family, placed in bands), from the springs' present state: a
  // cut since may have removed or rewired some (append_family skips the dead; the update that follows blanks
  // the rewired ones' new lanes and batches them again, as for any edited spring). Each family has its own
  // scratch, quads, runs and springs' slots, so the families are batched at once, as in the update.
#pragma omp parallel for num_threads(params_.threads > 1 ? 2 : 1) schedule(dynamic, 1)
  for (std::size_t f = 0; f < 3; ++f) append_family(cloth, loose_springs_, f);
  for (auto& bands : loose_bands_) bands.clear();
  loose_springs_.clear();
  loose_swept_ = false;
}

std::size_t Solver::loose_springs() const { return loose_springs_.size(); }

std::size_t Solver::unbanded_cut_quads() const {
  std::size_t quads = 0;
  for (const auto& runs : unbanded_runs_) {
    for (const QuadRun& r : runs) quads += r.end - r.begin;
  }
  for (const auto& bands : loose_bands_) {
    if (!bands.empty()) quads += bands.back().size();  // a quad each, in effect
  }
  return quads;
}

bool Solver::bands_independent() const {
  if (!banded_) return true;
  const std::size_t count = band_reach_.size();
  std::vector<std::uint32_t> owner;  // per padded particle: 1 + the band that last touched it, per parity
  for (std::size_t parity = 0; parity < 2; ++parity) {
    owner.assign(work_.size() + 1, 0);
    for (std::size_t j = parity; j < count; j += 2) {
      for (std::size_t f = 0; f < 3; ++f) {
        std::vector<QuadRun> runs = band_cut_runs_[f][j];
        runs.push_back({static_cast<std::uint32_t>(bands_[f][j]), static_cast<std::uint32_t>(bands_[f][j + 1])});
        const auto own = [&](std::uint32_t p) {
          if (p == 0) return true;
          if (p >= owner.size()) owner.resize(p + 1, 0);
          if (owner[p] != 0 && owner[p] != j + 1) return false;
          owner[p] = static_cast<std::uint32_t>(j + 1);
          return true;
        };
        for (const QuadRun& r : runs) {
          for (std::uint32_t q = r.begin; q < r.end; ++q) {
            for (std::size_t l = 0; l < 4; ++l) {
              if (!own(quads_[f][q].a[l]) || !own(quads_[f][q].b[l])) return false;
            }
          }
        }
        if (j < loose_bands_[f].size()) {
          for (const PackedSpring& sp : loose_bands_[f][j]) {
            if (!own(sp.a) || !own(sp.b)) return false;
          }
        }
      }
    }
  }
  return true;
}

void Solver::build_bands(const Cloth& cloth) {
  // A spring of row v (its upper end's row, the batches' order) touches rows v .. v + 2 (bend springs two
  // apart; structural and shear v .. v + 1). So bands of at least three rows, every other one swept at once,
  // share no particle: a two-colouring of a partition, where each band itself is still swept in the
  // single-threaded order. What a cut changes in place only blanks lanes (particle 0, which never moves);
  // its new springs are appended and placed in the band of their rows (place_cut_quads), or after the bands
  // where they fit none. The check below reads the particles' rows rather than trusting the
  // rule: after a full build of a cut cloth an exact cut's particles have the row of their nearest grid point.
  // The three families share the bands' rows, so that a band can sweep all of its springs at once.
  banded_ = false;
  for (auto& bounds : bands_) bounds.clear();
  for (auto& runs : band_cut_runs_) runs.clear();
  for (auto& runs : unbanded_runs_) runs.clear();
  band_first_row_.clear();
  band_reach_.clear();
  const int threads = params_.threads;
  if (threads <= 1) return;
  const auto row_of = [&](std::uint32_t padded) { return cloth.grid[padded - 1].v; };
  const auto first_row = [&](const SpringQuad& g) { return std::min(row_of(g.a[0]), row_of(g.b[0])); };
  int rows = 0;
  for (const auto& quads : quads_) {
    if (!quads.empty()) rows = std::max(rows, first_row(quads.back()) + 1);  // sorted by row (sweep_key)
  }
  const int count = 2 * threads;
  constexpr int kRowsPerBand = 3;
  if (rows < kRowsPerBand * count) return;
  std::vector<std::pair<int, int>> reach(static_cast<std::size_t>(count),
                                         {std::numeric_limits<int>::max(), std::numeric_limits<int>::min()});
  for (std::size_t f = 0; f < 3; ++f) {
    std::vector<std::size_t>& bounds = bands_[f];
    const std::vector<SpringQuad>& quads = quads_[f];
    bounds.resize(static_cast<std::size_t>(count) + 1);
    std::size_t at = 0;
    for (int j = 0; j < count; ++j) {
      const int from = rows * j / count;
      while (at < quads.size() && first_row(quads[at]) < from) ++at;
      bounds[static_cast<std::size_t>(j)] = at;
    }
    bounds.back() = quads.size();
    for (std::size_t j = 0; j < reach.size(); ++j) {
      for (std::size_t k = bounds[j]; k < bounds[j + 1]; ++k) {
        for (std::size_t l = 0; l < 4; ++l) {
          for (const std::uint32_t p : {quads[k].a[l], quads[k].b[l]}) {
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
  // The rows a cut's springs in band j may reach: those its own rows' springs may (a spring of row v touches
  // v .. v + 2), and none that another band of its parity reaches. Fixed until the next build, so each
  // quad's place depends on it alone (place_cut_quads).
  for (int j = 0; j < count; ++j) band_first_row_.push_back(rows * j / count);
  band_reach_.resize(static_cast<std::size_t>(count));
  for (std::size_t j = 0; j < reach.size(); ++j) {
    int from = band_first_row_[j];
    int to = j + 1 < reach.size() ? band_first_row_[j + 1] + 1 : std::numeric_limits<int>::max();
    if (j >= 2) from = std::max(from, reach[j - 2].second + 1);
    if (j + 2 < reach.size()) to = std::min(to, reach[j + 2].first - 1);
    band_reach_[j] = {from, to};
  }
  for (auto& runs : band_cut_runs_) runs.assign(static_cast<std::size_t>(count), {});
}

void Solver::sweep_band(Vec4* padded, std::size_t family, std::size_t band, float alpha) const {
  const SpringQuad* g = quads_[family].data();
  sweep_near_rest(padded, g + bands_[family][band], g + bands_[family][band + 1], alpha);
  for (const QuadRun& r : band_cut_runs_[family][band]) sweep_near_rest(padded, g + r.begin, g + r.end, alpha);
  if (band < loose_bands_[family].size()) sweep_loose(padded, loose_bands_[family][band], alpha);
}

void Solver::sweep_unbanded(Vec4* padded, std::size_t family, float alpha) const {
  const SpringQuad* g = quads_[family].data();
  for (const QuadRun& r : unbanded_runs_[family]) sweep_near_rest(padded, g + r.begin, g + r.end, alpha);
  if (!loose_bands_[family].empty()) sweep_loose(padded, loose_bands_[family].back(), alpha);
}

void Solver::sweep_springs(Vec4* padded, std::size_t family, float alpha) const {
  // Banded sweeps run in front_in_bands, inside the sub-step's one parallel region; this is the order of one
  // thread, or of several when the cloth has too few rows for bands (build_bands).
  const SpringQuad* g = quads_[family].data();
  sweep_near_rest(padded, g, g + quads_[family].size(), alpha);
}

}  // namespace tachi::sim
