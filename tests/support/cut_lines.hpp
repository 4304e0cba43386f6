// Comparing the cut lines (summary.json "cut_line": the grid points the cut passed) of two live runs.
#pragma once

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <utility>
#include <vector>

namespace tachi::test {

/// Whether two live runs of one recording cut the same line: every grid point of each run's cut line lies
/// within one cell (8-neighbourhood) of a point of the other's, both ways.
///
/// Why not cell for cell: the simulator locates each stroke sample on the cloth as the cloth is when the
/// sample arrives (sim/src/stroke.cpp, `grid_offset`: a live simulator cuts the cloth where it is now), and
/// the cloth moves while it is cut. A few milliseconds of delivery or scheduling move a point that lies near a
/// cell's edge across it: two runs of straight_cut on a loaded machine, their strokes identical, ended one
/// cell apart (20 and 21 points) in 1 of 10 pairs (2026-12-06), as a clean and a 10 %-loss run did in CI.
/// A line that lost or gained more than its last cell, or moved by more than a cell, still fails.
inline ::testing::AssertionResult cut_lines_agree_within_a_cell(const nlohmann::json& a_summary,
                                                                const nlohmann::json& b_summary) {
  const auto points = [](const nlohmann::json& summary) {
    std::vector<std::pair<int, int>> v;
    if (summary.contains("cut_line"))
      for (const auto& g : summary["cut_line"]) v.emplace_back(g[0].get<int>(), g[1].get<int>());
    return v;
  };
  const auto a = points(a_summary), b = points(b_summary);
  const auto near_one_of = [](std::pair<int, int> point, const std::vector<std::pair<int, int>>& line) {
    for (const auto& [u, v] : line)
      if (std::abs(point.first - u) <= 1 && std::abs(point.second - v) <= 1) return true;
    return false;
  };
  const auto describe = [&] {
    return "\n  " + a_summary.value("cut_line", nlohmann::json::array()).dump() + "\nvs\n  " +
           b_summary.value("cut_line", nlohmann::json::array()).dump();
  };
  if (a.empty() || b.empty()) return ::testing::AssertionFailure() << "a cut line is empty:" << describe();
  for (const auto& p : a)
    if (!near_one_of(p, b))
      return ::testing::AssertionFailure() << "(" << p.first << ", " << p.second << ") of the first is not within a cell of the second:" << describe();
  for (const auto& p : b)
    if (!near_one_of(p, a))
      return ::testing::AssertionFailure() << "(" << p.first << ", " << p.second << ") of the second is not within a cell of the first:" << describe();
  return ::testing::AssertionSuccess();
}

}  // namespace tachi::test
