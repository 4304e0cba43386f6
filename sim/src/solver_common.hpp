// What the solver's files share (sim/src/solver_*.cpp, spring_batches.cpp, strain_limit.cpp, tethers.cpp,
// tether_repair.cpp, tether_release.cpp): the "none" markers of its per-particle arrays, the padded position
// type, and the split of independent loops over threads (OpenMP). Private to tachi_sim.
#pragma once

#include "tachi/sim/cloth.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace tachi::sim::solver_detail {

inline constexpr std::uint32_t kNone = 0xFFFFFFFFU;
inline constexpr std::uint32_t kNoBend = 0xFFFFFFFEU;  // PinGroup::last_bend: checked, there is none
inline constexpr float kInf = std::numeric_limits<float>::infinity();

/// Whether a search has settled a particle, from its open flag and distance: reached, and not open for repair.
/// (Solver::seed reads only settled neighbours; settled_groups and the labelling of cut-off pieces use it.)
constexpr bool settled(std::uint8_t open, float dist) { return open == 0 && dist < kInf; }

/// A particle's position (x, y, z) with its inverse mass in w: one aligned 16-byte load (Solver::step).
using Vec4 = Eigen::Vector4f;
/// Masks the inverse mass out of a difference of two Vec4.
inline const Vec4 kXyz{1.0F, 1.0F, 1.0F, 0.0F};

/// Runs body(chunk, begin, end) over [0, n) in `threads` contiguous chunks at once (OpenMP, static: chunk t
/// on thread t), or in one call (chunk 0) for one thread or a short range. For loops whose iterations are
/// independent (each particle on its own, or tethers of distinct particles), so the results do not depend on
/// the split; the chunk's number lets a loop keep something per chunk (count_keys).
template <typename Body>
void for_numbered_chunks(std::size_t n, int threads, const Body& body) {
  constexpr std::size_t kWorthSplitting = 2048;  // below this the threads' wake-up costs more than the loop
  if (threads <= 1 || n < kWorthSplitting) {
    body(std::size_t{0}, std::size_t{0}, n);
    return;
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int t = 0; t < threads; ++t) {
    const auto chunk = static_cast<std::size_t>(t);
    const auto parts = static_cast<std::size_t>(threads);
    body(chunk, n * chunk / parts, n * (chunk + 1) / parts);
  }
}

/// for_numbered_chunks without the chunk's number: body(begin, end).
template <typename Body>
void for_chunks(std::size_t n, int threads, const Body& body) {
  for_numbered_chunks(n, threads, [&](std::size_t, std::size_t begin, std::size_t end) { body(begin, end); });
}

/// A stable counting sort of the indices [0, n) by a small integer key (distribution counting, Knuth, TAOCP
/// vol. 3, sec. 5.2), split over threads in contiguous chunks: each chunk counts its own keys
/// (count_keys), then places its indices after the earlier chunks' in each bucket (place_by_keys), so the
/// order is exactly one thread's. Two passes over the indices, each on every thread: the solver re-sorts its
/// tethers on each step of a repair (linear, but on one thread 0.13 ms of a 0.6 ms two-thread step at
/// 128 x 128; 0.10 ms on two). `next` is the caller's scratch: per chunk, per key, the count, then the next
/// position.
struct KeyTally {
  std::size_t buckets = 0;          ///< the largest key seen plus one
  std::size_t total = 0;            ///< indices counted
  std::size_t in_first_bucket = 0;  ///< indices with key 0
};

/// Counts key(i) over [0, n).
template <typename Key>
KeyTally count_keys(std::size_t n, int threads, const Key& key, std::vector<std::vector<std::uint32_t>>& next) {
  next.resize(static_cast<std::size_t>(std::max(threads, 1)));
  for (auto& counts : next) counts.clear();
  for_numbered_chunks(n, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t>& counts = next[chunk];
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t b = key(i);
      if (b >= counts.size()) counts.resize(static_cast<std::size_t>(b) + 1, 0);
      ++counts[b];
    }
  });
  KeyTally tally;
  for (const auto& counts : next) tally.buckets = std::max(tally.buckets, counts.size());
  // Each chunk's count of a bucket becomes where its first index of that bucket goes.
  for (std::size_t b = 0; b < tally.buckets; ++b) {
    for (auto& counts : next) {
      counts.resize(tally.buckets, 0);
      const std::uint32_t here = counts[b];
      counts[b] = static_cast<std::uint32_t>(tally.total);
      tally.total += here;
    }
    if (b == 0) tally.in_first_bucket = tally.total;
  }
  return tally;
}

/// Calls place(i, position) for every index in [0, n), position in [0, n): its place in the sorted order.
template <typename Key, typename Place>
void place_by_keys(std::size_t n, int threads, const Key& key, const Place& place,
                   std::vector<std::vector<std::uint32_t>>& next) {
  for_numbered_chunks(n, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t>& at = next[chunk];
    for (std::size_t i = begin; i < end; ++i) place(i, at[key(i)]++);
  });
}

/// A set of indices kept as a bit per index, for a log with repeats that is wanted once each and in
/// increasing order (the update after a cut: the springs it edited, the particles they touch). Marking is a
/// store per entry and the read-out one pass over the words, where sort + unique of the log was ~0.2 ms of
/// the update after a 64-segment exact cut at 128 x 128 (5,722 edits). The read-out is in increasing
/// order, as sort + unique gave it: the strain limit appends the edited springs in that order.
inline void mark_index(std::vector<std::uint64_t>& bits, std::uint32_t i) {
  bits[i >> 6U] |= std::uint64_t{1} << (i & 63U);
}

/// Appends the marked indices to `out` in increasing order and clears the marks.
inline void take_marked(std::vector<std::uint64_t>& bits, std::vector<std::uint32_t>& out) {
  for (std::size_t w = 0; w < bits.size(); ++w) {
    std::uint64_t word = bits[w];
    if (word == 0) continue;
    bits[w] = 0;
    for (; word != 0; word &= word - 1) {
      out.push_back(static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(std::countr_zero(word))));
    }
  }
}

}  // namespace tachi::sim::solver_detail
