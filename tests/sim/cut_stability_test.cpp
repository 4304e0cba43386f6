// Cuts that do not flip (docs/cutting.md, "Cuts that do not flip"): random hand-like strokes through the
// offline driver (blade contact, stroke cutter, solver), every blade and every cut mode.
//  * a stroke moved by 1e-6 m gives the same pieces and a cut length within 1 %;
//  * a stroke gone over forward, back and forward again gives the same pieces as once.
// The full 500 strokes: bench/sim/cut_stability (seeds 1000..; these use 5000..).
//  * docs/cutting.md's blade table is what blade_table() (cut_stability --blade-table) prints.
#include "paths.hpp"
#include "tachi/sim/cut_stability.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <unistd.h>
#include <utility>

namespace {

using namespace tachi::sim;

constexpr Blade kBlades[] = {Blade::Razor, Blade::Scalpel, Blade::Utility, Blade::Kitchen, Blade::Hunting, Blade::Worn};
constexpr CutMode kModes[] = {CutMode::Exact, CutMode::Grid, CutMode::Delete};
constexpr int kStrokes = 10;
constexpr std::uint64_t kFirstSeed = 5000;
constexpr int kGrid = 32;

std::filesystem::path scratch(const char* name) {
  return std::filesystem::temp_directory_path() / (std::string{name} + "_" + std::to_string(::getpid()) + ".csv");
}

// Ten strokes, every blade and mode. They pass since samples beyond the blade's reach cut nothing (session
// 27); the acceptance's 500 strokes do not yet: `cut_stability --strokes 500` (docs/cutting.md, "Cuts that do
// not flip", the 1e-6 m table) still finds strokes that flip, so this guards what holds, not the target.
TEST(CutStability, AStrokeMovedByAHairCutsTheSame) {
  const auto file = scratch("cut_stability_hair");
  for (int k = 0; k < kStrokes; ++k) {
    const std::uint64_t seed = kFirstSeed + static_cast<std::uint64_t>(k);
    const auto stroke = random_stroke(seed);
    const auto moved = perturbed(stroke, 1e-6, seed * 7919U);
    for (const Blade blade : kBlades) {
      for (const CutMode mode : kModes) {
        SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::string{to_string(blade)} + ", " + std::string{to_string(mode)});
        const CutOutcome a = cut_outcome(stroke, blade, mode, kGrid, file);
        const CutOutcome b = cut_outcome(moved, blade, mode, kGrid, file);
        EXPECT_EQ(a.pieces, b.pieces);
        EXPECT_LE(std::abs(a.cut_length_m - b.cut_length_m), 0.01 * std::max(a.cut_length_m, b.cut_length_m) + 1e-6);
      }
    }
  }
  std::filesystem::remove(file);
}

// The bend along a straight cut (docs/cutting.md, session 33): development stroke 279 enters the cloth across its
// left edge in a straight line; the exact cut's first segment has three new particles on one line, and which lip
// got the bend between two of them was the sign of a rounding error. With the stroke moved by 1e-6 m (as
// cut_stability moves it) it went to the other lip, the entry corner (two springs and a particle of 33 mg) jumped
// 0.14 mm in the next step whatever the hair's size (1e-6 or 1e-8 m), and the cut ended 1.036 against 0.820 m.
// Through the offline driver, razor, exact.
TEST(CutStability, TheBendAlongAStraightCutDoesNotFlipWithAHair) {
  const auto file = scratch("cut_stability_bend");
  constexpr std::uint64_t seed = 279;
  const auto stroke = random_stroke(seed);
  const auto moved = perturbed(stroke, 1e-6, seed ^ 0x9E3779B97F4A7C15ULL);
  const CutOutcome a = cut_outcome(stroke, Blade::Razor, CutMode::Exact, kGrid, file);
  const CutOutcome b = cut_outcome(moved, Blade::Razor, CutMode::Exact, kGrid, file);
  std::filesystem::remove(file);
  EXPECT_EQ(a.pieces, b.pieces);
  EXPECT_LE(std::abs(a.cut_length_m - b.cut_length_m), 0.01 * std::max(a.cut_length_m, b.cut_length_m));
}

// Development strokes that cut one piece, razor, 32 x 32, through the offline driver: gone there, back and there
// again, still one piece.
void expect_one_piece_gone_over_again(std::initializer_list<std::uint64_t> seeds, CutMode mode, const char* name) {
  const auto file = scratch(name);
  for (const std::uint64_t seed : seeds) {
    SCOPED_TRACE("development stroke " + std::to_string(seed));
    const auto stroke = random_stroke(seed);
    const CutOutcome once = cut_outcome(stroke, Blade::Razor, mode, kGrid, file);
    const CutOutcome again = cut_outcome(there_back_and_there(stroke), Blade::Razor, mode, kGrid, file);
    EXPECT_EQ(once.pieces, 1U);
    EXPECT_EQ(again.pieces, once.pieces);
  }
  std::filesystem::remove(file);
}

// A blade back in its slit (docs/cutting.md section 10, StrokeCutter::in_slit): going back along a cut, the hand
// comes down on material the hanging cloth has moved under it since (the cut opens, its flaps swing), up to a
// cell or more beside the cut. Development strokes 168 and 281 (razor, exact, 32 x 32) went there, back and
// there again through the offline driver and cut 2 and 4 pieces where once cut 1: a sliver off the lip where
// the stroke had come in across the edge. With the hand's own path deciding that it is back in its slit, the
// same piece as once.
TEST(CutStability, ABladeBackInItsSlitCutsNoSliverOffAMovedLip) {
  expect_one_piece_gone_over_again({168U, 281U}, CutMode::Exact, "cut_stability_slit");
}

// Grid mode cuts along staircases of grid edges (seed 000 eqs. (1)-(4)), rasterised from the grid point the
// line starts at. A pass back over a cut starts its line elsewhere and takes the other side of the cells the
// first staircase crossed diagonally, or lands a cell beside a cut whose flap swung: together the two ring
// cells, which fell. Development strokes 112, 180 and 196 (a ring of one cell), 224 (a strip one cell wide) and
// 251 (a cell between the cut and the cloth's edge), razor, grid, 32 x 32, gave 2 pieces where once gave 1.
// Stroke 1 (session 41): a line of a single step, from one cut particle to another a cell beside the cut, rings the
// cell between too (it gave 2 pieces once the blade in its slit went where its hand cut, before runs of one step
// were looked at).
TEST(CutStability, AGridCutGoneOverAgainRingsNoCell) {
  expect_one_piece_gone_over_again({1U, 112U, 180U, 196U, 224U, 251U}, CutMode::Grid, "cut_stability_grid_ring");
}

// A stroke that turns back along the line it is cutting: at the turn the hand stands while the cut opens and
// its flaps swing, so the material under it moves by up to a few cells; the way back counted the current line's
// last 2 cells of hand path as "going on" and cut beside the cut there. Development strokes 232 and 247 (exact)
// and 279 (grid), razor, 32 x 32: 2 pieces gone there, back and there again where once cut 1 (session 40; 51,
// also fixed then, differs again since session 41, on its way back far from the turn). And the cut's own last
// stretch (recut_parts): the way back from the turn re-cut the line's last third of a cell, along itself, and
// left a sliver triangle at the tip (development strokes 165, 237 and 280, exact: 2 pieces before session 41).
TEST(CutStability, AStrokeTurningBackAlongItsCutCutsNoSliverAtTheTurn) {
  expect_one_piece_gone_over_again({232U, 247U, 165U, 237U, 280U}, CutMode::Exact, "cut_stability_turn_exact");
  expect_one_piece_gone_over_again({279U}, CutMode::Grid, "cut_stability_turn_grid");
}

// A blade that left the cloth across its edge and comes back where it left: the line it cut is closed, and its
// last 2 cells were still left out as if it were being cut, so the way back came onto the cloth half a cell beside
// the cut and cut a sliver off the lip at the edge (development strokes 111, 135 and 248, razor, exact, 32 x 32:
// 2-3 pieces gone there, back and there again before session 41, 1 as once).
TEST(CutStability, ABladeBackWhereItLeftTheClothIsInItsSlit) {
  expect_one_piece_gone_over_again({111U, 135U, 248U}, CutMode::Exact, "cut_stability_left_edge");
}

// A blade back in its slit is where its hand was when it cut there (StrokeCutter::in_slit): the point of the cut
// its hand's nearest point of the earlier hand path cut, not the cut's point nearest to the material now under it.
// The flap swung 2-4 cells under the hand going back (development strokes 115 and 140, exact; 57, 116 and 206,
// delete). Razor, 32 x 32, through the offline driver: 2-4 pieces gone there, back and there before session 41.
// (Stroke 224, exact, which cuts 2 pieces once, differed for the same cause near an edge: five samples located
// beyond it all went to the cut's end there and the chord from it cut off a corner of the lip.)
TEST(CutStability, ABladeInItsSlitIsWhereItsHandCut) {
  expect_one_piece_gone_over_again({115U, 140U}, CutMode::Exact, "cut_stability_hand_exact");
  expect_one_piece_gone_over_again({57U, 116U, 206U}, CutMode::Delete, "cut_stability_hand_delete");
}

// A way back along the cut joins the path whether or not it meets the path within the small-loop perimeter
// (StrokeCutter::commit): it cuts nothing, so it bounds no island. Exact mode used to leave such a segment out, so
// the path's end stayed at the turn until a later point lay far enough off to close no small loop, and the chord
// from the turn to it cut across the bends between (development stroke 565: a corner off the first pass's bend
// 1 cell from the turn). Development strokes 565 and 764, razor, exact, 32 x 32: 2 pieces gone there, back and
// there again before session 42, 1 as once.
TEST(CutStability, AWayBackAlongTheCutFollowsItFromTheTurn) {
  expect_one_piece_gone_over_again({565U, 764U}, CutMode::Exact, "cut_stability_way_back");
}

// A pass ends where the hand turned back, as a stroke ending there does (StrokeCutter::add_sample's turn): the
// chord fit never committed the turn, so the pass stopped up to 2 cells short of it. Development strokes 166 and
// 826 cut across the cloth once and separate a piece (3 pieces); gone there, back and there the cut ended short
// of the edge it reached (2 pieces). 530: a sliver where a later pass cut the stretch the first left uncut (2
// pieces, 1 once). Razor, exact, 32 x 32, through the offline driver.
TEST(CutStability, APassEndsWhereTheHandTurnedBack) {
  const auto file = scratch("cut_stability_turn_apex");
  for (const auto& [seed, pieces] : {std::pair{166U, 3U}, std::pair{826U, 3U}, std::pair{530U, 1U}}) {
    SCOPED_TRACE("development stroke " + std::to_string(seed));
    const auto stroke = random_stroke(seed);
    const CutOutcome once = cut_outcome(stroke, Blade::Razor, CutMode::Exact, kGrid, file);
    const CutOutcome again = cut_outcome(there_back_and_there(stroke), Blade::Razor, CutMode::Exact, kGrid, file);
    EXPECT_EQ(once.pieces, pieces);
    EXPECT_EQ(again.pieces, once.pieces);
  }
  std::filesystem::remove(file);
}

// Random strokes 5000-5009 cut there, back and there again give the pieces cutting once gives, in every mode
// (the report seeds' figures, which still miss, are in docs/cutting.md section 10).
TEST(CutStability, GoingOverACutAgainChangesNothing) {
  const auto file = scratch("cut_stability_recut");
  for (int k = 0; k < kStrokes; ++k) {
    const std::uint64_t seed = kFirstSeed + static_cast<std::uint64_t>(k);
    const auto stroke = random_stroke(seed);
    for (const CutMode mode : kModes) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::string{to_string(mode)});
      const CutOutcome once = cut_outcome(stroke, Blade::Razor, mode, kGrid, file);
      const CutOutcome again = cut_outcome(there_back_and_there(stroke), Blade::Razor, mode, kGrid, file);
      EXPECT_EQ(once.pieces, again.pieces);
    }
  }
  std::filesystem::remove(file);
}

TEST(BladeTable, TheDocsTableIsWhatTheCommandPrints) {
  const auto file = scratch("blade_table");
  const std::string printed = blade_table(file);
  std::filesystem::remove(file);
  const std::string doc_path = tachi::test::source_dir() + "/docs/cutting.md";
  std::ifstream doc{doc_path};
  ASSERT_TRUE(doc) << doc_path;
  // The table in the doc: from its header line to the first line that is not a table row.
  const std::string header = printed.substr(0, printed.find('\n'));
  std::string in_doc;
  bool inside = false;
  for (std::string line; std::getline(doc, line);) {
    if (line == header) inside = true;
    if (inside && line.rfind('|', 0) != 0) break;
    if (inside) in_doc += line + "\n";
  }
  ASSERT_FALSE(in_doc.empty()) << "no table headed \"" << header << "\" in docs/cutting.md";
  EXPECT_EQ(in_doc, printed) << "regenerate it with build/bin/cut_stability --blade-table";
}

}  // namespace
