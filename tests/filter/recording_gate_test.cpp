// Threshold gating on the sensor's synthetic recordings, end to end through the real executables:
// tachi-sensor (depth frames -> hand CSV) then tachi-filter --offline (-> strokes).
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

using Table = std::vector<std::map<std::string, std::string>>;

Table read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream h(line);
    std::string c;
    while (std::getline(h, c, ',')) header.push_back(c);
  }
  Table rows;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string c;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; std::getline(s, c, ',') && i < header.size(); ++i) row[header[i]] = c;
    rows.push_back(row);
  }
  return rows;
}

using Interval = std::pair<long, long>;  // first and last frame

/// Maximal runs of frames for which `inside(row)` holds.
template <class F>
std::vector<Interval> runs(const Table& rows, F inside) {
  std::vector<Interval> out;
  for (const auto& row : rows) {
    const long frame = std::stol(row.at("frame"));
    if (!inside(row)) continue;
    if (!out.empty() && out.back().second == frame - 1)
      out.back().second = frame;
    else
      out.emplace_back(frame, frame);
  }
  return out;
}

/// Frames over which each stroke was open: cutting (gate 1) or holding (gate 2, the hand reaching in
/// or pulling out while the stroke stays open).
std::map<std::string, Interval> strokes(const Table& out) {
  std::map<std::string, Interval> s;
  for (const auto& row : out) {
    if (row.at("gate") == "0") continue;
    const long frame = std::stol(row.at("frame"));
    auto [it, fresh] = s.try_emplace(row.at("stroke_id"), frame, frame);
    if (!fresh) it->second.second = frame;
  }
  return s;
}

class RecordingGate : public ::testing::Test {
 protected:

  /// Plays a recording through the sensor and the filter; returns (ground truth, filter output).
  std::pair<Table, Table> run(const std::string& scenario) {
    const fs::path recording = fs::path(TACHI_RECORDINGS_DIR) / scenario;
    EXPECT_TRUE(fs::exists(recording / "INDEX.txt")) << recording;
    auto r = tachi::test::run({TACHI_SENSOR_EXE, "--recording", recording.string(), "--rate", "max", "--no-dds", "--csv",
                               (dir_ / "hands.csv").string()},
                              120s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    r = tachi::test::run({TACHI_FILTER_EXE, "--offline", "--hands", (dir_ / "hands.csv").string(), "--out",
                          (dir_ / "strokes.csv").string()},
                         60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return {read_csv(recording / "ground_truth.csv"), read_csv(dir_ / "strokes.csv")};
  }
  tachi::test::ScratchDir dir_{"recording_gate"};
};

// recordings/push: the hand pushes through the cloth plane (1.0 m from the sensor) and back, twice.
// Each push must be exactly one stroke, not several, and cover the frames in which the hand touched.
TEST_F(RecordingGate, EachPushTowardTheClothAndBackIsOneStroke) {
  const auto [truth, out] = run("push");
  // Touching: the true palm within the default enter distance (5 cm) of the cloth plane or through it.
  const auto touches = runs(truth, [](const auto& row) {
    return row.at("visible") == "1" && std::stod(row.at("z")) < 1.05;
  });
  ASSERT_EQ(touches.size(), 2U) << "the push recording should touch the cloth twice";
  const auto cut = strokes(out);
  ASSERT_EQ(cut.size(), 2U) << "one stroke per push";
  std::size_t i = 0;
  for (const auto& [id, frames] : cut) {
    const auto& touch = touches[i++];
    EXPECT_EQ(std::stoul(id), i);
    // Opens within the enter dwell plus the smoother's catch-up of the touch, closes after it.
    EXPECT_GE(frames.first, touch.first) << "stroke " << id;
    EXPECT_LE(frames.first, touch.first + 6) << "stroke " << id;
    EXPECT_GE(frames.second, touch.second) << "stroke " << id;
    EXPECT_LE(frames.second, touch.second + 10) << "stroke " << id;
  }
}

// recordings/jitter: one slow cut through the cloth plane (0.98 m) with 6 mm tremor: one stroke.
TEST_F(RecordingGate, AJitteryCutIsOneStroke) {
  const auto [truth, out] = run("jitter");
  EXPECT_EQ(strokes(out).size(), 1U);
}

}  // namespace
