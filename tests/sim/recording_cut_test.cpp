// The bundled straight_cut recording through the real sensor and filter (offline, no DDS), then its strokes
// through the simulator's Session sample by sample with the filter's gate, as the live simulator takes
// them: every cut mode must leave what grid mode leaves, one slit (exact mode used to cut the recorded
// hand's stroke into 3-10 pieces, because the hand wobbles at the end of its stroke and the nearest
// particle sometimes lies on another layer of the moving cloth).
#include "paths.hpp"
#include "tachi/sim/offline.hpp"
#include "tachi/sim/pieces.hpp"
#include "tachi/sim/session.hpp"

#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using tachi::sim::CutMode;

/// One row of tachi-filter's offline output: frame,stamp_ns,x,y,z,gate,stroke_id.
struct FilteredSample {
  double t_s = 0.0;
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  int gate = 0;  // GateState: idle, cutting, holding, grabbing
  std::uint32_t stroke_id = 0;
};

std::vector<FilteredSample> read_filtered(const fs::path& path) {
  std::ifstream in{path};
  std::string line;
  std::getline(in, line);
  std::vector<FilteredSample> rows;
  while (std::getline(in, line)) {
    std::stringstream cells{line};
    std::vector<std::string> c;
    for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
    if (c.size() != 7) continue;
    rows.push_back({std::stod(c[1]) * 1e-9, {std::stof(c[2]), std::stof(c[3]), std::stof(c[4])}, std::stoi(c[5]),
                    static_cast<std::uint32_t>(std::stoul(c[6]))});
  }
  return rows;
}

/// Pieces left after the recording's strokes on a top-edge pinned cloth, samples fed between 60 Hz steps
/// at their own times (the first half a second after the start, as the offline driver does).
std::size_t pieces_after(const std::vector<FilteredSample>& rows, CutMode mode, int grid) {
  tachi::sim::OfflineOptions o;
  o.cloth.columns = grid;
  o.cloth.rows = grid;
  o.cloth.pin = tachi::sim::PinMode::TopEdge;
  o.cut_mode = mode;
  tachi::sim::Session session{tachi::sim::session_options(o)};
  const double t0 = rows.front().t_s - 0.5;
  const double dt = session_options(o).solver.dt;
  std::size_t next = 0;
  for (int s = 0; s < 420; ++s) {
    while (next < rows.size() && rows[next].t_s - t0 < (s + 1) * dt) {
      const FilteredSample& r = rows[next++];
      tachi::sim::HandInput hand;
      hand.stroke_id = r.stroke_id;
      hand.time_s = r.t_s - t0;
      hand.position_m = r.position;
      hand.tracked = r.position.allFinite();
      hand.cutting = r.gate == 1;
      hand.holding = r.gate == 2;
      session.on_hand(hand);
    }
    session.step();
  }
  session.end_stroke();
  return tachi::sim::find_pieces(session.cloth()).count();
}

TEST(RecordingCut, TheStraightCutRecordingLeavesOneSlitInExactModeAsInGridMode) {
  const tachi::test::ScratchDir scratch{"sim_recording_cut"};
  const fs::path recording = fs::path(tachi::test::recordings_dir()) / "straight_cut";
  ASSERT_TRUE(fs::exists(recording / "INDEX.txt")) << recording;
  const fs::path hands = scratch / "hands.csv";
  const fs::path strokes = scratch / "strokes.csv";
  auto r = tachi::test::run({tachi::test::executable("tachi-sensor"), "--recording", recording.string(), "--rate", "max", "--no-dds", "--csv",
                             hands.string(), "--log-level", "warn"},
                            60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = tachi::test::run({tachi::test::executable("tachi-filter"), "--offline", "--hands", hands.string(), "--out", strokes.string()}, 60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = read_filtered(strokes);
  ASSERT_GT(rows.size(), 100U);
  std::size_t cutting = 0;
  for (const auto& row : rows) cutting += row.gate == 1 ? 1U : 0U;
  ASSERT_GT(cutting, 50U) << "the filter's gate opened a stroke";
  // 64 is the launcher's grid (exact mode: 3 pieces before); 128 showed the locator's spike (8 pieces).
  for (const int grid : {32, 64, 128}) {
    const std::size_t grid_pieces = pieces_after(rows, CutMode::Grid, grid);
    EXPECT_EQ(grid_pieces, 1U) << grid << ": grid mode leaves one slit";
    EXPECT_EQ(pieces_after(rows, CutMode::Exact, grid), grid_pieces) << grid << " x " << grid << ", exact mode";
  }
}

}  // namespace
