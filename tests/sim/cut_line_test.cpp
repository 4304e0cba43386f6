#include "tachi/sim/cut_line.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

namespace tachi::sim {
namespace {

std::vector<GridCoord> path(std::initializer_list<GridCoord> p) { return p; }

void expect_connected(const std::vector<GridCoord>& line) {
  for (std::size_t i = 1; i < line.size(); ++i) {
    EXPECT_TRUE(grid_adjacent(line[i - 1], line[i]))
        << "step " << i << ": (" << line[i - 1].u << "," << line[i - 1].v << ") -> (" << line[i].u << ","
        << line[i].v << ")";
  }
}

TEST(CutLine, RasterisesTheWorkedSlopeExample) {
  // a = 2/4: v = 0.5 -> 0 at u=1, v = 1 -> 1 at u=2, v = 0.5 -> 0 at u=3, v = 1 -> 1 at u=4 (eqs. (3)-(4)).
  EXPECT_EQ(rasterise_segment({0, 0}, {4, 2}), path({{0, 0}, {1, 0}, {2, 0}, {2, 1}, {3, 1}, {4, 1}, {4, 2}}));
}

TEST(CutLine, StraightHorizontalIsTheRow) {
  EXPECT_EQ(rasterise_segment({2, 3}, {5, 3}), path({{2, 3}, {3, 3}, {4, 3}, {5, 3}}));
}

TEST(CutLine, SteepSegmentDescendsInEachColumn) {
  // a = 5: at u=1, v = 5 -> five rows down in that column.
  EXPECT_EQ(rasterise_segment({0, 0}, {1, 5}), path({{0, 0}, {1, 0}, {1, 1}, {1, 2}, {1, 3}, {1, 4}, {1, 5}}));
}

TEST(CutLine, NegativeSlopeRoundsTowardsZero) {
  // a = -2/3: v = -0.67 -> 0, v = -1.33 -> -1, then the rest; eq. (4)'s -[|v|] branch.
  EXPECT_EQ(rasterise_segment({0, 5}, {3, 3}), path({{0, 5}, {1, 5}, {2, 5}, {2, 4}, {3, 4}, {3, 3}}));
}

TEST(CutLine, VerticalSegmentIsTheColumn) {
  EXPECT_EQ(rasterise_segment({4, 1}, {4, 4}), path({{4, 1}, {4, 2}, {4, 3}, {4, 4}}));
  EXPECT_EQ(rasterise_segment({4, 4}, {4, 2}), path({{4, 4}, {4, 3}, {4, 2}}));
}

TEST(CutLine, RightToLeftIsTheReverseOfLeftToRight) {
  auto forward = rasterise_segment({1, 2}, {9, 7});
  auto backward = rasterise_segment({9, 7}, {1, 2});
  std::reverse(backward.begin(), backward.end());
  EXPECT_EQ(forward, backward);
  EXPECT_EQ(rasterise_segment({9, 7}, {1, 2}).front(), (GridCoord{9, 7}));
}

TEST(CutLine, RepeatedParticleIsASinglePoint) {
  EXPECT_EQ(rasterise_segment({3, 3}, {3, 3}), path({{3, 3}}));
  CutLineBuilder b{10, 10};
  b.append({3, 3});
  EXPECT_TRUE(b.append({3, 3}).empty());
  EXPECT_EQ(b.line().size(), 1U);
}

TEST(CutLine, RandomSegmentsAreConnectedMinimalAndNearTheLine) {
  std::mt19937 rng{7};
  std::uniform_int_distribution<int> coord{0, 40};
  for (int trial = 0; trial < 3000; ++trial) {
    const GridCoord a{coord(rng), coord(rng)};
    const GridCoord b{coord(rng), coord(rng)};
    const auto line = rasterise_segment(a, b);
    ASSERT_EQ(line.front(), a);
    ASSERT_EQ(line.back(), b);
    // A monotone staircase: exactly one particle per unit step, so nothing is visited twice.
    ASSERT_EQ(line.size(), static_cast<std::size_t>(std::abs(b.u - a.u) + std::abs(b.v - a.v) + 1));
    expect_connected(line);
    // Truncation lags the exact line by less than a row, so in column u every particle lies within
    // |slope| + 1 rows of it.
    if (a.u != b.u) {
      const double slope = static_cast<double>(b.v - a.v) / (b.u - a.u);
      for (const GridCoord g : line) {
        const double exact = a.v + slope * (g.u - a.u);
        ASSERT_LE(std::abs(g.v - exact), std::abs(slope) + 1.0);
      }
    }
  }
}

TEST(CutLine, StartAtTopEdgeStepsInBeforeFollowingTheSlope) {
  CutLineBuilder b{12, 12};
  b.append({5, 0});
  b.append({10, 3});
  const auto& line = b.line();
  ASSERT_GE(line.size(), 2U);
  EXPECT_EQ(line[0], (GridCoord{5, 0}));
  EXPECT_EQ(line[1], (GridCoord{5, 1}));  // seed 000 Figure 2 (b): (u_i, v_i + 1)
  EXPECT_EQ(line.back(), (GridCoord{10, 3}));
  expect_connected(line);
  for (std::size_t i = 1; i < line.size(); ++i) EXPECT_GT(line[i].v, 0) << "the line follows the top edge";
}

TEST(CutLine, StartAtBottomEdgeStepsUp) {
  CutLineBuilder b{12, 12};
  b.append({2, 11});
  b.append({9, 8});
  const auto& line = b.line();
  EXPECT_EQ(line[1], (GridCoord{2, 10}));
  for (std::size_t i = 1; i < line.size(); ++i) EXPECT_LT(line[i].v, 11);
  expect_connected(line);
}

TEST(CutLine, VerticalCutFromTheTopNeedsNoExtraParticle) {
  CutLineBuilder b{8, 8};
  b.append({3, 0});
  b.append({3, 7});
  EXPECT_EQ(b.line().size(), 8U);
  EXPECT_EQ(b.line()[1], (GridCoord{3, 1}));
}

TEST(CutLine, RunAlongTheEdgeBeforeEnteringIsDropped) {
  CutLineBuilder b{10, 10};
  b.append({0, 6});
  b.append({0, 2});  // slides up the left edge: cuts nothing
  EXPECT_EQ(b.line(), path({{0, 2}}));
  b.append({4, 2});
  EXPECT_EQ(b.line(), path({{0, 2}, {1, 2}, {2, 2}, {3, 2}, {4, 2}}));
}

TEST(CutLine, RunAlongTheEdgeAfterReachingItIsTrimmedAtTheEnd) {
  CutLineBuilder b{64, 64};
  b.append({60, 10});
  b.append({63, 17});  // reaches the right edge at (63, 14), then slides down it
  const auto& line = b.finish();
  EXPECT_EQ(line.back(), (GridCoord{63, 14}));
  expect_connected(line);
}

TEST(CutLine, BuilderReturnsOnlyTheNewEdges) {
  CutLineBuilder b{10, 10};
  EXPECT_EQ(b.append({2, 2}), path({{2, 2}}));
  EXPECT_EQ(b.append({4, 2}), path({{2, 2}, {3, 2}, {4, 2}}));
  EXPECT_EQ(b.append({4, 4}), path({{4, 2}, {4, 3}, {4, 4}}));
  EXPECT_EQ(b.line().size(), 5U);
}

TEST(CutLine, PointsOffTheGridAreClamped) {
  CutLineBuilder b{5, 5};
  b.append({-3, 2});
  b.append({9, 2});
  EXPECT_EQ(b.finish(), path({{0, 2}, {1, 2}, {2, 2}, {3, 2}, {4, 2}}));
}

TEST(CutLine, LengthIsInRestMetres) {
  const auto line = path({{0, 0}, {1, 0}, {1, 1}, {2, 1}});
  EXPECT_FLOAT_EQ(cut_line_length(line, 0.1F, 0.2F), 0.1F + 0.2F + 0.1F);
}

}  // namespace
}  // namespace tachi::sim
