// Long-range attachments (Kim, Chentanez, Mueller 2012), sub-step step 2: each particle is held within its
// rest distance of each pin group (one Dijkstra search over the springs per group, build_attachments). Behind a
// cut a tether follows the geodesic: it holds the particle to the last particle before the shortest path bends
// around the cut (attach, nearest_bend, is_bend_point), itself held first (order_tethers). A tether that comes
// after a cut tightens over steps (engage_tethers). The sweep of all tethers, on several threads per pin
// group's block (sweep_all_tethers). Repairs after a cut: tether_repair.cpp and tether_release.cpp.
#include "tachi/sim/solver.hpp"

#include "constraint_kernels.hpp"
#include "solver_common.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace tachi::sim {

using solver_detail::for_chunks;
using solver_detail::kInf;
using solver_detail::kNoBend;
using solver_detail::kNone;
using solver_detail::Vec4;

namespace {

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

using solver_detail::sweep_tethers;

std::size_t Solver::attachment_count() const {
  return static_cast<std::size_t>(std::count_if(attachments_.begin(), attachments_.end(),
                                                [](const Attachment& a) { return std::isfinite(a.length2); }));
}

void Solver::attach(const Cloth& cloth, PinGroup& group, std::uint32_t i, bool engage) {
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
  if (group.last_bend.size() < cloth.particle_count()) {
    group.last_bend.resize(cloth.particle_count(), kNone);
    group.bend_checked.resize(cloth.particle_count(), 0);
  }
  const std::uint32_t parent = group.parent[i];
  if (cloth.inverse_mass[i] != 0.0F && std::isfinite(group.dist[i]) && parent != kNone) {
    const bool parent_is_pin = cloth.inverse_mass[parent] == 0.0F;
    const std::uint32_t candidate = parent_is_pin ? parent : group.anchor[parent];
    const bool past_bend = candidate != kNone && cloth.inverse_mass[candidate] != 0.0F;
    const float lip_detour = past_bend ? std::min(cloth.spacing_x(), cloth.spacing_y()) : 0.0F;
    const auto straight_from = [&](std::uint32_t a) {
      return group.dist[i] - group.dist[a] <= octile(cloth, cloth.rest_uv[i], cloth.rest_uv[a]) * (1.0F + 1e-4F) +
                                                   off_grid(cloth, i) + off_grid(cloth, a) + lip_detour + 1e-6F;
    };
    if (candidate == kNone) {
      anchor = parent;
    } else if (straight_from(candidate)) {
      anchor = candidate;  // last_bend stays unknown: found by a walk if a descendant's path bends
    } else {
      const std::uint32_t bend = parent == candidate ? kNoBend : nearest_bend(cloth, group, parent, candidate);
      // None: a detour of the discretisation, the candidate stays. Either way nothing between the anchor and
      // i can bend.
      anchor = bend != kNoBend ? bend : candidate;
      last_bend = kNoBend;
    }
    const float length = cloth.rest_distance(i, anchor);
    length2 = length * length;
    bends = cloth.inverse_mass[anchor] == 0.0F ? 0 : group.bends[anchor] + 1;
  }
  group.anchor[i] = anchor;
  group.last_bend[i] = last_bend;
  group.bend_checked[i] = cloth.topology_version;
  if (bends != group.bends[i]) (group.apart.active ? group.apart.order_stale : tether_order_stale_) = true;
  group.bends[i] = bends;
  std::uint32_t& slot = group.attachment[i];
  // Already in engaging_ (a later repair settling it again): listed once, so it tightens at one speed.
  const bool listed = slot != kNone && std::isfinite(attachments_[slot].length2) &&
                      attachments_[slot].reach2 > attachments_[slot].length2;
  if (slot == kNone) {
    if (!std::isfinite(length2)) return;
    // Never while the groups repair apart (run_apart): a particle a cut appended got its slot then
    // (update_attachments), and only those come to a repair without one.
    assert(!group.apart.active);
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
      if (!listed) (group.apart.active ? group.apart.engaging : engaging_).push_back(slot);
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

std::uint32_t Solver::nearest_bend(const Cloth& cloth, PinGroup& group, std::uint32_t from, std::uint32_t anchor) {
  // The nearest particle where the path can bend, from `from` (included) up to `anchor` (excluded). A record
  // is trusted when it names a particle, or says "none" checked since the last topology change: a cut makes
  // new bend points (a tip) without reopening the particles whose paths pass them, so their old "none" may
  // be out of date. What a walk finds is written back on the particles it passed: each is walked through at
  // most once per topology version (walking every branch again cost a 128 x 128 long stroke 50 ms steps).
  std::uint32_t found = kNoBend;
  std::uint32_t p = from;
  for (; p != anchor && p != kNone; p = group.parent[p]) {
    if (is_bend_point(cloth, p)) {
      found = p;
      break;
    }
    const std::uint32_t known = group.last_bend[p];
    if (known != kNone && (known != kNoBend || group.bend_checked[p] == cloth.topology_version)) {
      found = known;
      break;
    }
  }
  for (std::uint32_t q = from; q != p && q != kNone; q = group.parent[q]) {
    group.last_bend[q] = found;
    group.bend_checked[q] = cloth.topology_version;
  }
  return found;
}

void Solver::order_tethers() {
  // A tether is applied after its anchor's own (fewer bends): a stable counting sort by bends, linear in the
  // tethers, on every thread (count_keys, place_by_keys: the same order as one thread's). A repair re-sorts on
  // each of its steps (the bends it settles change): on one thread that was 0.18-0.2 ms of a 0.6 ms
  // two-thread step at 128 x 128 (docs/benchmarks.md).
  tether_order_stale_ = false;
  const std::size_t count = attachments_.size();
  const auto bends = [this](std::size_t k) { return attachments_[k].bends; };
  const solver_detail::KeyTally tally = solver_detail::count_keys(count, params_.threads, bends, sort_scratch_);
  if (tally.buckets <= 1) {  // none bends: the attachments' own order is fine
    tether_order_.clear();
    return;
  }
  unbent_tethers_ = tally.in_first_bucket;
  // Every entry is written below: resized, not cleared first (zeroing 265k entries each step of a stroke).
  tether_order_.resize(count);
  solver_detail::place_by_keys(
      count, params_.threads, bends,
      [this](std::size_t k, std::uint32_t at) { tether_order_[at] = static_cast<std::uint32_t>(k); }, sort_scratch_);
}

void Solver::build_attachments(const Cloth& cloth) {
  attachments_.clear();
  engaging_.clear();
  tether_order_stale_ = true;
  tether_block_end_.clear();
  pin_groups_.clear();
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
    for (const std::uint32_t pin : cached_pins_) pin_groups_.emplace_back().sources = {pin};
  } else {
    std::vector<std::uint32_t> sorted = cached_pins_;
    std::sort(sorted.begin(), sorted.end(), [&](std::uint32_t a, std::uint32_t b) {
      const auto& ua = cloth.rest_uv[a];
      const auto& ub = cloth.rest_uv[b];
      return ua.x() != ub.x() ? ua.x() < ub.x() : ua.y() < ub.y();
    });
    const auto half = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    pin_groups_.emplace_back().sources = {sorted.front()};
    pin_groups_.emplace_back().sources.assign(sorted.begin(), half);
    pin_groups_.emplace_back().sources.assign(half, sorted.end());
    pin_groups_.emplace_back().sources = {sorted.back()};
  }
  const std::size_t particle_room = cloth.position.capacity();
  reserve_touched(attachments_, pin_groups_.size() * particle_room);
  reserve_touched(tether_order_, pin_groups_.size() * particle_room);
  for (PinGroup& group : pin_groups_) {
    reserve_touched(group.dist, particle_room);
    reserve_touched(group.parent, particle_room);
    reserve_touched(group.parent_spring, particle_room);
    reserve_touched(group.order_pos, particle_room);
    reserve_touched(group.order, 2 * particle_room);
    reserve_touched(group.owner, particle_room);
    reserve_touched(group.attachment, particle_room);
    reserve_touched(group.anchor, particle_room);
    reserve_touched(group.bends, particle_room);
    reserve_touched(group.last_bend, particle_room);
    reserve_touched(group.bend_checked, particle_room);
    reserve_touched(group.open, particle_room);
    reserve_touched(group.open_list, particle_room);
    reserve_touched(group.heap, particle_room);
    group.dist.assign(n, kInf);
    group.parent.assign(n, kNone);
    group.parent_spring.assign(n, kNone);
    group.order_pos.assign(n, kNone);
    group.order.clear();
    group.seeded = 0;
    group.owner.assign(n, kNone);
    group.attachment.assign(n, kNone);
    group.anchor.assign(n, kNone);
    group.bends.assign(n, 0);
    group.last_bend.assign(n, kNone);
    group.bend_checked.assign(n, 0);
    group.open.assign(n, 0);
    group.open_list.clear();
    group.open_count = 0;
    group.heap.clear();
    for (const std::uint32_t s : group.sources) {
      group.dist[s] = 0.0F;
      group.owner[s] = s;
      group.heap.emplace_back(0.0F, s);
    }
    const std::size_t block_begin = attachments_.size();
    std::size_t unbounded = std::numeric_limits<std::size_t>::max();
    search_paths(cloth, group, false, unbounded);
    // The group's tethers by particle, not in the order the search settled them: each holds another particle
    // on a pin, so they are independent and the order changes nothing, but a thread can then find the
    // tethers of its range of particles (front_in_bands), and the sweep reads the positions in order.
    std::size_t next = block_begin;
    std::vector<Attachment> by_particle;
    by_particle.reserve(attachments_.size() - block_begin);
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint32_t& slot = group.attachment[i];
      if (slot == kNone) continue;
      by_particle.push_back(attachments_[slot]);
      slot = static_cast<std::uint32_t>(next++);
    }
    std::copy(by_particle.begin(), by_particle.end(), attachments_.begin() + static_cast<std::ptrdiff_t>(block_begin));
    tether_block_end_.push_back(attachments_.size());
    for (std::uint32_t i = 0; i < n; ++i) nearest_[i] = std::min(nearest_[i], group.dist[i]);
  }
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

}  // namespace tachi::sim
