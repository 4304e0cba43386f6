// Threshold gating on the sensor's synthetic recordings, end to end through the real executables:
// tachi-sensor (depth frames -> hand CSV) then tachi-filter --offline (-> strokes).
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
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
  std::pair<Table, Table> run(const std::string& scenario, const std::vector<std::string>& filter_flags = {}) {
    const fs::path recording = fs::path(tachi::test::recordings_dir()) / scenario;
    EXPECT_TRUE(fs::exists(recording / "INDEX.txt")) << recording;
    auto r = tachi::test::run({tachi::test::executable("tachi-sensor"), "--recording", recording.string(), "--rate", "max", "--no-dds", "--csv",
                               (dir_ / "hands.csv").string()},
                              120s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::vector<std::string> filter{tachi::test::executable("tachi-filter"), "--offline", "--hands", (dir_ / "hands.csv").string(), "--out",
                                    (dir_ / "strokes.csv").string()};
    filter.insert(filter.end(), filter_flags.begin(), filter_flags.end());
    r = tachi::test::run(filter, 60s);
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

// recordings/jitter through tachi-sensor and tachi-filter's default smoother (One Euro as published):
// against the path without tremor, on the stroke itself (intended speed < 0.5 m/s), it halves the raw
// error once its lag is removed, and that lag is at most one frame (docs/filter.md, "Smoothing").
TEST_F(RecordingGate, TheDefaultSmootherHalvesTheTremorWithinAFrameOfLag) {
  const auto [truth, out] = run("jitter", {"--camera-frame"});
  const auto hands = read_csv(dir_ / "hands.csv");
  std::map<long, std::array<double, 3>> intended;
  for (const auto& row : truth)
    intended[std::stol(row.at("frame"))] = {std::stod(row.at("intended_x")), std::stod(row.at("intended_y")),
                                            std::stod(row.at("intended_z"))};
  const auto stroke_frame = [&](long f) {
    const auto a = intended.find(f), b = intended.find(f + 1);
    if (a == intended.end() || b == intended.end() || truth.at(static_cast<std::size_t>(f)).at("visible") != "1") return false;
    double d2 = 0;
    for (int i = 0; i < 3; ++i) d2 += (b->second[i] - a->second[i]) * (b->second[i] - a->second[i]);
    return std::sqrt(d2) * 30.0 < 0.5;
  };
  // RMS distance to the intended path shifted by `shift` frames (linear between frames).
  const auto rms_at = [&](const Table& rows, double shift) {
    double sum = 0;
    int n = 0;
    for (const auto& row : rows) {
      const long f = std::stol(row.at("frame"));
      if (row.at("x") == "nan" || (row.count("tracked") && row.at("tracked") != "1") || !stroke_frame(f)) continue;
      const double t = static_cast<double>(f) - shift;
      const auto a = intended.find(static_cast<long>(std::floor(t))), b = intended.find(static_cast<long>(std::floor(t)) + 1);
      if (a == intended.end() || b == intended.end()) continue;
      const double w = t - std::floor(t);
      const std::array<double, 3> p{std::stod(row.at("x")), std::stod(row.at("y")), std::stod(row.at("z"))};
      for (int i = 0; i < 3; ++i) {
        const double q = (1 - w) * a->second[i] + w * b->second[i];
        sum += (p[i] - q) * (p[i] - q);
      }
      ++n;
    }
    return n > 50 ? std::sqrt(sum / n) : 1e9;
  };
  const auto best = [&](const Table& rows) {
    std::pair<double, double> b{1e9, 0};  // (rms, shift)
    for (double shift = -3.0; shift <= 6.0; shift += 0.05) b = std::min(b, std::pair{rms_at(rows, shift), shift});
    return b;
  };
  const auto [raw_rms, raw_lag] = best(hands);
  const auto [smooth_rms, smooth_lag] = best(out);
  EXPECT_LT(raw_rms, 0.02);  // the sensor's samples: tremor (6 mm per axis) plus sensor error
  EXPECT_LE(smooth_rms, 0.5 * raw_rms) << "raw " << raw_rms << " m, smoothed " << smooth_rms << " m";
  EXPECT_LE(smooth_lag, 1.0);
  EXPECT_GE(smooth_lag, 0.0);
}

}  // namespace
