// Disjoint sets over 0 .. n-1 (union-find with path halving; Tarjan 1975, path halving after Tarjan and
// van Leeuwen 1984): the one used for a cloth's pieces (pieces.cpp) and for the groups of a particle's
// triangle fan that stay connected across uncut edges (cutting.cpp, exact_cut.cpp), and for the open
// particles' components when a cut-off piece loses its tethers (tether_release.cpp). The storage is kept
// between uses (reset), so a cut that splits fans allocates nothing once it has grown.
#pragma once

#include <cstddef>
#include <numeric>
#include <utility>
#include <vector>

namespace tachi::sim {

template <typename Index = std::size_t>
class UnionFind {
 public:
  UnionFind() = default;
  explicit UnionFind(std::size_t n) { reset(n); }

  /// n singletons.
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), Index{0});
  }
  [[nodiscard]] std::size_t size() const { return parent_.size(); }
  /// Room for n elements, its pages touched now, so a reset to n later neither allocates nor faults (the
  /// solver sizes it to the cloth's room for cuts before the first timed step).
  void reserve(std::size_t n) {
    if (n <= parent_.capacity()) return;
    const std::size_t size = parent_.size();
    parent_.reserve(n);
    parent_.resize(n);
    parent_.resize(size);
  }

  /// The representative of i's set: its smallest member is not promised, only that it is the same for
  /// every member until the next unite.
  Index find(Index i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  /// The same representative as find, without shortening the path on the way: it writes nothing, so several
  /// threads may ask at once (after finds have shortened the paths, it is about as quick).
  [[nodiscard]] Index root(Index i) const {
    while (parent_[i] != i) i = parent_[i];
    return i;
  }
  /// Joins the sets of a and b; false when they were one already. The larger root goes under the smaller,
  /// so a set's representative is the smallest root it absorbed (the result does not depend on the order
  /// of the unions' arguments).
  bool unite(Index a, Index b) {
    Index ra = find(a);
    Index rb = find(b);
    if (ra == rb) return false;
    if (rb < ra) std::swap(ra, rb);
    parent_[rb] = ra;
    return true;
  }

 private:
  std::vector<Index> parent_;
};

}  // namespace tachi::sim
