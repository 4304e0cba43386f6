#include "tachi/sim/cutting.hpp"

#include "tachi/sim/cut_line.hpp"
#include "tachi/sim/pieces.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <gtest/gtest.h>

#include "cut_test_support.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace tachi::sim {
namespace {

using test::make_cloth;
using test::total_mass;
using test::triangle_pieces;

std::vector<GridCoord> line_through(std::initializer_list<GridCoord> points, int columns, int rows) {
  const std::vector<GridCoord> p(points);
  return build_cut_line(p, columns, rows);
}

/// How many cut edges meet at grid coordinate g.
int cut_degree(const ClothCutter& cutter, GridCoord g) {
  int n = 0;
  for (const GridCoord d : {GridCoord{1, 0}, GridCoord{-1, 0}, GridCoord{0, 1}, GridCoord{0, -1}}) {
    if (cutter.edge_cut(g, {g.u + d.u, g.v + d.v})) ++n;
  }
  return n;
}

/// The invariants every cut must keep: springs and triangles name existing particles and are
/// in the incidence lists; mass is conserved; particle count grows by exactly the duplicates; no
/// triangle or spring bridges the cut.
void expect_invariants(const Cloth& cloth, const ClothCutter& cutter, std::size_t particles_before,
                       std::size_t duplicated, double mass_before) {
  const std::size_t n = cloth.particle_count();
  ASSERT_EQ(n, particles_before + duplicated);
  ASSERT_EQ(cloth.mass.size(), n);
  ASSERT_EQ(cloth.velocity.size(), n);
  ASSERT_EQ(cloth.grid.size(), n);
  ASSERT_NEAR(total_mass(cloth), mass_before, 1e-6 * mass_before);
  const int columns = cloth.columns;
  const int rows = cloth.rows;
  std::set<std::pair<std::uint32_t, std::uint32_t>> pairs;
  // Mesh edges (particle pairs) -> triangles having them.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> mesh_edges;
  for (std::uint32_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    for (int i = 0; i < 3; ++i) {
      ASSERT_LT(tri[i], n);
      ASSERT_TRUE(std::find(cloth.triangles_of(tri[i]).begin(), cloth.triangles_of(tri[i]).end(), t) !=
                  cloth.triangles_of(tri[i]).end());
      const std::uint32_t a = tri[i];
      const std::uint32_t b = tri[(i + 1) % 3];
      ++mesh_edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (std::uint32_t k = 0; k < cloth.spring_count(); ++k) {
    if (cloth.alive[k] == 0) continue;
    const std::uint32_t a = cloth.spring_a[k];
    const std::uint32_t b = cloth.spring_b[k];
    ASSERT_LT(a, n);
    ASSERT_LT(b, n);
    ASSERT_NE(a, b);
    ASSERT_TRUE(std::find(cloth.springs_of(a).begin(), cloth.springs_of(a).end(), k) != cloth.springs_of(a).end());
    ASSERT_TRUE(std::find(cloth.springs_of(b).begin(), cloth.springs_of(b).end(), k) != cloth.springs_of(b).end());
    ASSERT_TRUE(pairs.insert({std::min(a, b), std::max(a, b)}).second) << "two springs on one particle pair";
    const GridCoord ga = cloth.grid[a];
    const GridCoord gb = cloth.grid[b];
    if (cloth.kind[k] == SpringKind::Bend) {
      // A bend survives only as the chain of two live structural springs, neither of them cut.
      const GridCoord gm{(ga.u + gb.u) / 2, (ga.v + gb.v) / 2};
      ASSERT_FALSE(cutter.edge_cut(ga, gm));
      ASSERT_FALSE(cutter.edge_cut(gm, gb));
      bool chained = false;
      for (const std::uint32_t s1 : cloth.springs_of(a)) {
        if (cloth.kind[s1] != SpringKind::Structural) continue;
        const std::uint32_t m = cloth.spring_a[s1] == a ? cloth.spring_b[s1] : cloth.spring_a[s1];
        if (!(cloth.grid[m] == gm)) continue;
        for (const std::uint32_t s2 : cloth.springs_of(m)) {
          if (cloth.kind[s2] == SpringKind::Structural && (cloth.spring_a[s2] == b || cloth.spring_b[s2] == b)) chained = true;
        }
      }
      ASSERT_TRUE(chained) << "bend spring " << k << " bridges the cut";
    } else if (cloth.kind[k] == SpringKind::Structural ||
               (ga.u - gb.u) * (ga.v - gb.v) > 0) {  // structural or the mesh diagonal (u,v)-(u+1,v+1)
      ASSERT_TRUE(mesh_edges.count({std::min(a, b), std::max(a, b)}) != 0)
          << "spring " << k << " is not an edge of any triangle";
    } else {
      // The other diagonal: its ends must sit in the two triangles of one cell that share a diagonal.
      bool found = false;
      for (const std::uint32_t ta : cloth.triangles_of(a)) {
        for (const std::uint32_t tb : cloth.triangles_of(b)) {
          int shared = 0;
          for (const std::uint32_t x : cloth.triangles[ta]) {
            const auto& other = cloth.triangles[tb];
            if (std::find(other.begin(), other.end(), x) != other.end()) ++shared;
          }
          if (shared >= 2) found = true;
        }
      }
      ASSERT_TRUE(found) << "diagonal spring " << k << " spans two separated triangles";
    }
  }
  // No triangle pair shares a cut edge unless the cut edge is a closed one-edge slit (both ends are
  // interior particles with no other cut edge: a particle-duplication model cannot open it).
  for (const auto& [edge, count] : mesh_edges) {
    const GridCoord ga = cloth.grid[edge.first];
    const GridCoord gb = cloth.grid[edge.second];
    if (count < 2 || !cutter.edge_cut(ga, gb)) continue;
    const bool closed_slit = !on_boundary(ga, columns, rows) && !on_boundary(gb, columns, rows) &&
                             cut_degree(cutter, ga) == 1 && cut_degree(cutter, gb) == 1;
    ASSERT_TRUE(closed_slit) << "two triangles still share the cut edge (" << ga.u << "," << ga.v << ")-(" << gb.u
                             << "," << gb.v << ")";
  }
  // Springs connect exactly what triangles connect.
  ASSERT_EQ(find_pieces(cloth).count(), triangle_pieces(cloth));
}

struct CutCase {
  Cloth cloth;
  ClothCutter cutter;
  explicit CutCase(Cloth c) : cloth(std::move(c)), cutter(cloth) {}
  CutCase(const CutCase&) = delete;
  CutCase& operator=(const CutCase&) = delete;

  TopologyChange cut_checked(const std::vector<GridCoord>& line) {
    const std::size_t before = cloth.particle_count();
    const double mass = total_mass(cloth);
    auto change = cutter.cut(line);
    expect_invariants(cloth, cutter, before, change.duplicated_from.size(), mass);
    return change;
  }
};

TEST(Cutting, LeftSideOfAStraightCutIsTheThreeNeighboursAhead) {
  // Moving right (+u), the left is up the screen (-v): Figure 3 (a) for a straight cut.
  const auto left = left_side_neighbours({-1, 0}, {1, 0});
  EXPECT_EQ(left, (std::vector<GridCoord>{{1, -1}, {0, -1}, {-1, -1}}));
  // Moving down (+v), the left is +u.
  const auto down = left_side_neighbours({0, -1}, {0, 1});
  ASSERT_EQ(down.size(), 3U);
  for (const GridCoord d : down) EXPECT_EQ(d.u, 1);
}

TEST(Cutting, LeftSideAtACornerIsTheInsideOrOutsideOfTheTurn) {
  // Right then up (a left turn): only the diagonal inside the turn is on the left.
  EXPECT_EQ(left_side_neighbours({-1, 0}, {0, -1}), (std::vector<GridCoord>{{-1, -1}}));
  // Right then down (a right turn): the five neighbours outside the turn.
  EXPECT_EQ(left_side_neighbours({-1, 0}, {0, 1}).size(), 5U);
  EXPECT_FALSE(left_of_cut({-1, 0}, {0, 1}, -1.0, 1.0));
}

TEST(Cutting, InteriorSlitDuplicatesTheInnerParticlesAndMovesTheLeftSprings) {
  CutCase c{make_cloth(10, 10)};
  const auto line = line_through({{2, 5}, {7, 5}}, 10, 10);
  const auto change = c.cut_checked(line);
  // Tips stay whole (a slit), the four particles between them get copies.
  ASSERT_EQ(change.duplicated_from.size(), 4U);
  EXPECT_EQ(find_pieces(c.cloth).count(), 1U);
  for (std::size_t i = 0; i < change.duplicated_from.size(); ++i) {
    const std::uint32_t copy = change.particle_count_before + static_cast<std::uint32_t>(i);
    const GridCoord g = c.cloth.grid[copy];
    EXPECT_EQ(g.v, 5);
    // The copy's neighbours are the left side of Figure 3 plus its two neighbours along the cut.
    std::set<std::pair<int, int>> offsets;
    for (const std::uint32_t k : c.cloth.springs_of(copy)) {
      if (c.cloth.kind[k] == SpringKind::Bend) continue;
      const std::uint32_t x = c.cloth.spring_a[k] == copy ? c.cloth.spring_b[k] : c.cloth.spring_a[k];
      offsets.insert({c.cloth.grid[x].u - g.u, c.cloth.grid[x].v - g.v});
    }
    std::set<std::pair<int, int>> expected{{-1, 0}, {1, 0}};
    for (const GridCoord d : left_side_neighbours({-1, 0}, {1, 0})) expected.insert({d.u, d.v});
    EXPECT_EQ(offsets, expected) << "copy of (" << g.u << "," << g.v << ")";
  }
  EXPECT_EQ(change.version, 1U);
  EXPECT_EQ(c.cloth.topology_version, 1U);
}

TEST(Cutting, FullWidthCutOfATopPinnedClothDropsTheLowerPiece) {
  CutCase c{make_cloth(12, 12)};
  c.cut_checked(line_through({{0, 6}, {11, 6}}, 12, 12));
  const Pieces pieces = find_pieces(c.cloth);
  ASSERT_EQ(pieces.count(), 2U);
  EXPECT_EQ(pieces.fallen(), 1U);
  Solver solver;
  const float y_top = c.cloth.position[c.cloth.index(5, 3)].y();
  const float y_bottom = c.cloth.position[c.cloth.index(5, 10)].y();
  for (int i = 0; i < 30; ++i) solver.step(c.cloth);
  // Half a second of free fall is ~1.2 m; the pinned half only sags.
  EXPECT_LT(c.cloth.position[c.cloth.index(5, 10)].y(), y_bottom - 0.5F);
  EXPECT_GT(c.cloth.position[c.cloth.index(5, 3)].y(), y_top - 0.2F);
}

TEST(Cutting, CurvedCutFromTheTopEdgeOpensAtTheEdge) {
  CutCase c{make_cloth(16, 16)};
  const auto line = line_through({{4, 0}, {6, 5}, {9, 8}, {13, 9}}, 16, 16);
  EXPECT_EQ(line[1], (GridCoord{4, 1}));
  const auto change = c.cut_checked(line);
  // Every particle but the interior end is duplicated (the start is on the edge).
  EXPECT_EQ(change.duplicated_from.size(), line.size() - 1);
  EXPECT_EQ(find_pieces(c.cloth).count(), 1U);
}

TEST(Cutting, CutFromTheBottomEdgeToTheTopSeparates) {
  CutCase c{make_cloth(10, 10)};
  const auto line = line_through({{3, 9}, {6, 0}}, 10, 10);
  c.cut_checked(line);
  const Pieces pieces = find_pieces(c.cloth);
  EXPECT_EQ(pieces.count(), 2U);
  EXPECT_EQ(pieces.fallen(), 0U);  // both halves keep part of the pinned top edge
}

TEST(Cutting, RightToLeftCutsTheSameEdges) {
  CutCase forward{make_cloth(12, 12)};
  CutCase backward{make_cloth(12, 12)};
  const auto a = forward.cut_checked(line_through({{1, 2}, {10, 8}}, 12, 12));
  const auto b = backward.cut_checked(line_through({{10, 8}, {1, 2}}, 12, 12));
  EXPECT_EQ(a.duplicated_from.size(), b.duplicated_from.size());
  for (int v = 0; v < 12; ++v) {
    for (int u = 0; u + 1 < 12; ++u) {
      EXPECT_EQ(forward.cutter.edge_cut({u, v}, {u + 1, v}), backward.cutter.edge_cut({u, v}, {u + 1, v}));
    }
  }
}

TEST(Cutting, VerticalCutThroughTheWholeClothGivesTwoPinnedHalves) {
  CutCase c{make_cloth(9, 9)};
  c.cut_checked(line_through({{4, 0}, {4, 8}}, 9, 9));
  const Pieces pieces = find_pieces(c.cloth);
  EXPECT_EQ(pieces.count(), 2U);
  EXPECT_EQ(pieces.fallen(), 0U);
}

TEST(Cutting, ClosedLoopCutsOutAFallingPatch) {
  CutCase c{make_cloth(12, 12)};
  c.cut_checked(line_through({{3, 3}, {8, 3}, {8, 8}, {3, 8}, {3, 3}}, 12, 12));
  const Pieces pieces = find_pieces(c.cloth);
  ASSERT_EQ(pieces.count(), 2U);
  EXPECT_EQ(pieces.fallen(), 1U);
  const std::uint32_t inner = pieces.piece_of[c.cloth.index(5, 5)];
  EXPECT_EQ(pieces.size[inner], 6U * 6U);  // particles (3..8) x (3..8), the ring duplicated
}

TEST(Cutting, CrossingCutsGiveFourPieces) {
  CutCase c{make_cloth(10, 10)};
  c.cut_checked(line_through({{0, 5}, {9, 5}}, 10, 10));
  c.cut_checked(line_through({{4, 0}, {4, 9}}, 10, 10));
  const Pieces pieces = find_pieces(c.cloth);
  EXPECT_EQ(pieces.count(), 4U);
  EXPECT_EQ(pieces.fallen(), 2U);
}

TEST(Cutting, ProgressiveCutEqualsTheWholeCut) {
  const auto line = line_through({{0, 3}, {5, 6}, {11, 4}}, 12, 12);
  CutCase whole{make_cloth(12, 12)};
  whole.cut_checked(line);
  CutCase pieces_of{make_cloth(12, 12)};
  std::size_t duplicated = 0;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    duplicated += pieces_of.cut_checked({line[i], line[i + 1]}).duplicated_from.size();
  }
  EXPECT_EQ(duplicated, whole.cloth.particle_count() - 144U);
  EXPECT_EQ(find_pieces(pieces_of.cloth).count(), find_pieces(whole.cloth).count());
  EXPECT_EQ(find_pieces(whole.cloth).count(), 2U);
}

TEST(Cutting, CuttingTheSameLineTwiceChangesNothing) {
  CutCase c{make_cloth(10, 10)};
  const auto line = line_through({{0, 4}, {9, 7}}, 10, 10);
  c.cut_checked(line);
  const auto version = c.cloth.topology_version;
  const auto again = c.cut_checked(line);
  EXPECT_TRUE(again.empty());
  EXPECT_EQ(c.cloth.topology_version, version);
}

TEST(Cutting, ChangeListNamesExactlyWhatChanged) {
  CutCase c{make_cloth(16, 16)};
  const auto triangles_before = c.cloth.triangles;
  const auto a_before = c.cloth.spring_a;
  const auto b_before = c.cloth.spring_b;
  const auto alive_before = c.cloth.alive;
  const auto change = c.cut_checked(line_through({{0, 8}, {7, 5}, {15, 9}}, 16, 16));
  std::vector<std::uint32_t> tri_changed;
  for (std::uint32_t t = 0; t < triangles_before.size(); ++t) {
    if (c.cloth.triangles[t] != triangles_before[t]) tri_changed.push_back(t);
  }
  EXPECT_EQ(change.changed_triangles, tri_changed);
  std::vector<std::uint32_t> spring_changed;
  for (std::uint32_t k = 0; k < c.cloth.spring_count(); ++k) {
    if (k >= a_before.size() || c.cloth.spring_a[k] != a_before[k] || c.cloth.spring_b[k] != b_before[k] ||
        c.cloth.alive[k] != alive_before[k]) {
      spring_changed.push_back(k);
    }
  }
  EXPECT_EQ(change.changed_springs, spring_changed);
  for (std::size_t i = 0; i < change.duplicated_from.size(); ++i) {
    EXPECT_EQ(c.cloth.grid[change.particle_count_before + i], c.cloth.grid[change.duplicated_from[i]]);
  }
}

TEST(Cutting, ChangesOfAStrokeMergeIntoOneList) {
  CutCase c{make_cloth(12, 12)};
  const auto line = line_through({{0, 6}, {11, 6}}, 12, 12);
  TopologyChange stroke;
  stroke.merge(c.cut_checked({line.begin(), line.begin() + 6}));
  const TopologyChange second = c.cut_checked({line.begin() + 5, line.end()});
  const auto first_before = stroke.particle_count_before;
  const auto first_duplicates = stroke.duplicated_from.size();
  stroke.merge(second);
  EXPECT_EQ(stroke.particle_count_before, first_before);
  EXPECT_EQ(stroke.particle_count_before, 144U);
  EXPECT_EQ(stroke.version, second.version);
  EXPECT_EQ(stroke.duplicated_from.size(), first_duplicates + second.duplicated_from.size());
  EXPECT_EQ(stroke.particle_count_before + stroke.duplicated_from.size(), c.cloth.particle_count());
  EXPECT_TRUE(std::is_sorted(stroke.changed_springs.begin(), stroke.changed_springs.end()));
  EXPECT_TRUE(std::adjacent_find(stroke.changed_triangles.begin(), stroke.changed_triangles.end()) ==
              stroke.changed_triangles.end());
}

TEST(Cutting, TouchesOnlyTheNeighbourhoodOfTheLine) {
  CutCase c{make_cloth(32, 32)};
  const auto line = line_through({{5, 10}, {20, 14}}, 32, 32);
  const auto change = c.cut_checked(line);
  const auto near_line = [&](std::uint32_t p) {
    const GridCoord g = c.cloth.grid[p];
    return std::any_of(line.begin(), line.end(), [&](GridCoord l) {
      return std::abs(l.u - g.u) <= 2 && std::abs(l.v - g.v) <= 2;
    });
  };
  for (const std::uint32_t k : change.changed_springs) {
    EXPECT_TRUE(near_line(c.cloth.spring_a[k]) || near_line(c.cloth.spring_b[k]));
  }
  for (const std::uint32_t t : change.changed_triangles) EXPECT_TRUE(near_line(c.cloth.triangles[t][0]));
}

TEST(Cutting, BadLinesAreSkipped) {
  CutCase c{make_cloth(6, 6)};
  EXPECT_TRUE(c.cut_checked({}).empty());
  EXPECT_TRUE(c.cut_checked({{2, 2}}).empty());
  EXPECT_TRUE(c.cut_checked({{-5, 2}, {-4, 2}, {1, 1}, {3, 3}, {40, 40}}).empty());
}

TEST(Cutting, ThousandsOfRandomLinesKeepTheInvariants) {
  std::mt19937 rng{20240611};
  int cuts = 0;
  for (int cloth_i = 0; cloth_i < 150; ++cloth_i) {
    const int columns = std::uniform_int_distribution<int>{2, 14}(rng);
    const int rows = std::uniform_int_distribution<int>{2, 14}(rng);
    const auto pin = static_cast<PinMode>(std::uniform_int_distribution<int>{0, 2}(rng));
    CutCase c{make_cloth(columns, rows, pin)};
    const int strokes = std::uniform_int_distribution<int>{1, 15}(rng);
    for (int s = 0; s < strokes; ++s) {
      std::vector<GridCoord> points;
      const int n = std::uniform_int_distribution<int>{1, 8}(rng);
      for (int i = 0; i < n; ++i) {
        points.push_back({std::uniform_int_distribution<int>{-2, columns + 1}(rng),
                          std::uniform_int_distribution<int>{-2, rows + 1}(rng)});
      }
      // Half the strokes are cut in one go, half progressively, point by point, as the hand moves.
      if (s % 2 == 0) {
        c.cut_checked(build_cut_line(points, columns, rows));
      } else {
        CutLineBuilder builder{columns, rows};
        for (const GridCoord p : points) c.cut_checked(builder.append(p));
      }
      ++cuts;
      if (HasFatalFailure()) {
        ADD_FAILURE() << "cloth " << cloth_i << " (" << columns << "x" << rows << ") stroke " << s;
        return;
      }
    }
  }
  EXPECT_GT(cuts, 1000);
}

TEST(Cutting, RandomHandStrokesOnAMovingClothKeepTheInvariants) {
  // Whole pipeline: world-space strokes (inside, outside, jittery, looping) through the StrokeCutter on
  // random grids, the cloth stepping between samples so it is deformed and partly falling.
  std::mt19937 rng{99};
  int strokes_done = 0;
  std::size_t total_duplicated = 0;
  for (int cloth_i = 0; cloth_i < 120; ++cloth_i) {
    const int columns = std::uniform_int_distribution<int>{2, 16}(rng);
    const int rows = std::uniform_int_distribution<int>{2, 16}(rng);
    Cloth cloth = make_cloth(columns, rows, static_cast<PinMode>(std::uniform_int_distribution<int>{0, 2}(rng)));
    StrokeOptions options;
    options.blade = static_cast<Blade>(std::uniform_int_distribution<int>{0, 5}(rng));
    StrokeCutter cutter{cloth, options};
    Solver solver;
    std::uniform_real_distribution<float> coord{-0.7F, 0.7F};
    std::normal_distribution<float> wobble{0.0F, 0.02F};
    const int strokes = std::uniform_int_distribution<int>{1, 6}(rng);
    for (int s = 0; s < strokes; ++s) {
      const std::size_t before = cloth.particle_count();
      const double mass = total_mass(cloth);
      std::size_t duplicated = 0;
      duplicated += cutter.begin_stroke().duplicated_from.size();
      Eigen::Vector3f p{coord(rng), coord(rng), wobble(rng)};
      const Eigen::Vector3f target{coord(rng), coord(rng), 0.0F};
      const int samples = std::uniform_int_distribution<int>{1, 40}(rng);
      for (int i = 0; i < samples; ++i) {
        p += (target - p) * 0.15F + Eigen::Vector3f{wobble(rng), wobble(rng), wobble(rng)};
        duplicated += cutter.add_sample({0.01 * i, p}).duplicated_from.size();
        if (i % 8 == 0) solver.step(cloth);
      }
      duplicated += cutter.end_stroke().duplicated_from.size();
      expect_invariants(cloth, cutter.cutter(), before, duplicated, mass);
      ++strokes_done;
      total_duplicated += duplicated;
      if (HasFatalFailure()) {
        ADD_FAILURE() << "cloth " << cloth_i << " (" << columns << "x" << rows << ") stroke " << s;
        return;
      }
    }
  }
  EXPECT_GT(strokes_done, 300);
  std::printf("random hand strokes: %d strokes duplicated %zu particles\n", strokes_done, total_duplicated);
  EXPECT_GT(total_duplicated, 1000U);  // the strokes really cut
}

}  // namespace
}  // namespace tachi::sim
