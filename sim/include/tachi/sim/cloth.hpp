// The cloth: Provot's mass-spring model (Provot 1995; seed 001 section 2.1) on an N x M particle grid,
// with a triangle mesh kept one-to-one with the particles (seed 001 Figure 2) for rendering and cutting.
// Everything lives in flat structure-of-arrays vectors so the solver streams through memory and a cut
// (seed 000 section 3.3, seed 001 section 3) can duplicate particles and rewire springs IN PLACE.
// Layout contract shared with the cutting code: /tmp/tachi_sim_contract.md, summarised in docs/sim.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace tachi::sim {

/// Original grid coordinate of a particle: u = column (0 at the left, x grows with u),
/// v = row (0 at the TOP, y decreases with v). A duplicate keeps its original's coordinate.
struct GridCoord {
  int u = 0;
  int v = 0;
  friend bool operator==(const GridCoord&, const GridCoord&) = default;
};

/// Provot's three spring families: structural (4-neighbours), shear (diagonals), bend (2 apart).
enum class SpringKind : std::uint8_t { Structural, Shear, Bend };

/// Which particles are fixed in space.
enum class PinMode : std::uint8_t { Corners, TopEdge, None };

/// Reserves and touches the room (grow, then shrink back: capacity stays), so the pages are mapped now
/// and not faulted in one by one by later push_backs (the first cut of a 256 x 256 cloth faulted in ~1200
/// pages of the solver's arrays, ~10 ms of that step). Every element of the room is written: an Eigen
/// vector's default constructor writes nothing, so a plain resize left those pages unmapped, and the first
/// step of a 256 x 256 cloth faulted in the solver's 2 MB of working positions (512 faults, 1.7 ms of its
/// 5.7 ms); the step after a cut faulted in the pages of its new particles.
template <typename T>
void reserve_touched(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  const std::size_t size = v.size();
  v.reserve(n);
  if constexpr (requires { T::Zero(); }) {
    v.resize(n, T::Zero());
  } else {
    v.resize(n, T{});
  }
  v.resize(size);
}

/// A short list of indices stored inline (no heap) until it outgrows `N`; then it moves to the heap.
/// Incidence lists are tiny (a grid particle has <= 12 springs and <= 6 triangles), so the inline
/// case is the only one in practice; the spill keeps a pathological rewiring correct instead of fatal.
template <std::size_t N>
class SmallIndexList {
 public:
  [[nodiscard]] std::span<const std::uint32_t> items() const {
    return spill_.empty() ? std::span<const std::uint32_t>{inline_.data(), count_}
                          : std::span<const std::uint32_t>{spill_};
  }
  [[nodiscard]] std::size_t size() const { return spill_.empty() ? count_ : spill_.size(); }
  void push_back(std::uint32_t x);
  /// Removes one occurrence of x (order not kept). Returns false if x was not present.
  bool erase(std::uint32_t x);
  [[nodiscard]] bool contains(std::uint32_t x) const;

 private:
  std::array<std::uint32_t, N> inline_{};
  std::uint32_t count_ = 0;
  std::vector<std::uint32_t> spill_;  // used only once inline_ overflowed
};

template <std::size_t N>
inline void SmallIndexList<N>::push_back(std::uint32_t x) {
  if (spill_.empty() && count_ < N) {
    inline_[count_++] = x;
    return;
  }
  if (spill_.empty()) {
    spill_.assign(inline_.begin(), inline_.begin() + count_);
    count_ = 0;
  }
  spill_.push_back(x);
}

template <std::size_t N>
inline bool SmallIndexList<N>::erase(std::uint32_t x) {
  if (!spill_.empty()) {
    const auto it = std::find(spill_.begin(), spill_.end(), x);
    if (it == spill_.end()) return false;
    *it = spill_.back();
    spill_.pop_back();
    return true;
  }
  for (std::uint32_t i = 0; i < count_; ++i) {
    if (inline_[i] == x) {
      inline_[i] = inline_[count_ - 1];
      --count_;
      return true;
    }
  }
  return false;
}

template <std::size_t N>
inline bool SmallIndexList<N>::contains(std::uint32_t x) const {
  const auto list = items();
  return std::find(list.begin(), list.end(), x) != list.end();
}

/// Construction parameters of a rectangular cloth.
struct ClothConfig {
  int columns = 64;           ///< particles along x (u), >= 2
  int rows = 64;              ///< particles along y (v), >= 2
  float width_m = 1.0F;       ///< extent along x
  float height_m = 1.0F;      ///< extent along y
  float total_mass_kg = 0.2F; ///< spread evenly over the particles
  PinMode pin = PinMode::Corners;
};

/// Returns a message naming the bad field, or nothing when the config can build a cloth.
[[nodiscard]] std::optional<const char*> validate(const ClothConfig& config);

/// Mass-spring cloth in structure-of-arrays form (see the file comment). Public data on purpose:
/// the solver and the cutting code read and write the arrays directly; the member functions keep
/// the arrays and the incidence lists consistent when the topology changes.
class Cloth {
 public:
  using SpringList = SmallIndexList<16>;
  using TriangleList = SmallIndexList<8>;

  /// Builds the grid of `config` hanging in the z = 0 plane, x right, y up, centred at the origin,
  /// with structural, shear and bend springs and two triangles per cell. Precondition: validate(config).
  explicit Cloth(const ClothConfig& config);
  Cloth() = default;

  // --- particles (all arrays have particle_count() entries) ---
  std::vector<Eigen::Vector3f> position;
  std::vector<Eigen::Vector3f> velocity;
  std::vector<float> mass;
  std::vector<float> inverse_mass;  ///< 0 = does not move (pinned or held by the hand)
  std::vector<GridCoord> grid;      ///< original grid coordinate (a particle made by an exact cut: the nearest one)
  /// Rest (material) coordinate in grid cells, u right and v down like GridCoord: (u, v) for a grid particle,
  /// anywhere on the cloth for a particle an exact cut made on an edge. Rest lengths come from it.
  std::vector<Eigen::Vector2f> rest_uv;
  std::vector<std::uint8_t> pinned;
  int columns = 0;
  int rows = 0;

  // --- springs (rewired in place; a removed spring keeps its slot with alive = 0) ---
  std::vector<std::uint32_t> spring_a;
  std::vector<std::uint32_t> spring_b;
  std::vector<float> rest_length;
  std::vector<SpringKind> kind;
  std::vector<std::uint8_t> alive;

  // --- triangles, counter-clockwise seen from +z; every edge is a structural or shear spring ---
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint8_t> triangle_alive;

  /// Bumped by every topology change made through the member functions below (and by anyone who
  /// edits the spring/triangle arrays directly): solvers cache derived data keyed on it.
  std::uint32_t topology_version = 0;

  [[nodiscard]] std::size_t particle_count() const { return position.size(); }
  [[nodiscard]] std::size_t spring_count() const { return spring_a.size(); }
  [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
  [[nodiscard]] std::size_t alive_spring_count() const;
  [[nodiscard]] std::size_t alive_triangle_count() const;
  [[nodiscard]] float spacing_x() const { return spacing_x_; }
  [[nodiscard]] float spacing_y() const { return spacing_y_; }
  /// Index of the uncut grid particle at (u, v): v * columns + u.
  [[nodiscard]] std::uint32_t index(int u, int v) const {
    return static_cast<std::uint32_t>(v * columns + u);
  }

  /// Reserves room for `particles` particles and `springs` springs, so that cuts appending particles and
  /// springs do not reallocate every array mid-frame (a first reallocation of a 128 x 128 cloth costs ~20 ms
  /// here, mostly page faults). The room is touched now, so later appends do not fault pages in either.
  /// Never shrinks.
  void reserve(std::size_t particles, std::size_t springs, std::size_t triangle_slots = 0);

  /// Appends a copy of particle i (position, velocity, grid coordinate, pinned) and splits i's mass
  /// in half between i and the copy, so total mass is conserved. Returns the copy's index.
  std::size_t duplicate_particle(std::size_t i);

  /// Appends a particle on the segment from a to b at fraction t (position, velocity and rest coordinate
  /// interpolated) with mass `new_mass`, fixed only when both ends are. The caller takes that mass from
  /// the neighbours (mass is conserved by the caller). Returns its index.
  std::size_t add_particle_between(std::size_t a, std::size_t b, float t, float new_mass);
  /// Sets particle i's mass, keeping its inverse mass 0 when it is fixed (pinned or held).
  void set_mass(std::size_t i, float new_mass);

  /// Appends a live spring a-b of `kind` with rest length from the rest coordinates of a and b and
  /// the grid spacing. Returns its index.
  std::uint32_t add_spring(std::uint32_t a, std::uint32_t b, SpringKind spring_kind);
  /// Marks spring k dead and drops it from its endpoints' incidence lists. Idempotent.
  void remove_spring(std::uint32_t k);
  /// Replaces endpoint `old_endpoint` of spring k by `new_endpoint`, updating the incidence.
  /// Returns false (and changes nothing) if old_endpoint is not an endpoint of k.
  bool rewire_spring(std::uint32_t k, std::uint32_t old_endpoint, std::uint32_t new_endpoint);

  /// Appends a live triangle. Returns its index.
  std::uint32_t add_triangle(std::array<std::uint32_t, 3> vertices);
  /// Marks triangle t dead and drops it from its vertices' incidence lists. Idempotent.
  void remove_triangle(std::uint32_t t);
  /// Replaces vertex `old_vertex` of triangle t by `new_vertex`. Returns false if not a vertex of t.
  bool rewire_triangle(std::uint32_t t, std::uint32_t old_vertex, std::uint32_t new_vertex);

  /// Live springs touching particle i (indices into the spring arrays).
  [[nodiscard]] std::span<const std::uint32_t> springs_of(std::size_t i) const {
    return spring_incidence_[i].items();
  }
  /// Live triangles having particle i as a vertex.
  [[nodiscard]] std::span<const std::uint32_t> triangles_of(std::size_t i) const {
    return triangle_incidence_[i].items();
  }

  /// Fixes or frees particle i in place (inverse mass follows).
  void set_pinned(std::size_t i, bool is_pinned);

  /// Rest length that a spring between grid coordinates a and b has on this cloth.
  [[nodiscard]] float grid_rest_length(GridCoord a, GridCoord b) const;
  /// Rest distance between particles i and j (from their rest coordinates), metres.
  [[nodiscard]] float rest_distance(std::size_t i, std::size_t j) const;

  /// Spring indices in the order they were added, removed or rewired (a spring may appear more than
  /// once). Never cleared: a solver keeps how far it has read and updates only those springs.
  std::vector<std::uint32_t> spring_edits;

  /// Largest (length / rest length - 1) over live structural springs; 0 for a cloth without any.
  [[nodiscard]] float max_structural_strain() const;

 private:
  float spacing_x_ = 0.0F;
  float spacing_y_ = 0.0F;
  std::vector<SpringList> spring_incidence_;
  std::vector<TriangleList> triangle_incidence_;
};

/// Particles a pin mode fixes on a columns x rows grid (corners = the two top corners).
[[nodiscard]] std::vector<std::uint32_t> pinned_particles(int columns, int rows, PinMode pin);

}  // namespace tachi::sim
