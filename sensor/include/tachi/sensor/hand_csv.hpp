// CSV files of hand samples (what tachi-sensor writes, one row per depth frame) and of ground
// truth (what tachi-synth writes), and the evaluation that compares them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tachi/sensor/hand_finder.hpp"

namespace tachi::sensor {

inline constexpr const char* kHandCsvHeader = "frame,stamp_ns,x,y,z,u,v,tracked,confidence";

/// One row of a hand CSV (positions are 0 when not tracked).
struct HandRow {
  std::uint64_t frame = 0;
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double u = 0, v = 0;
  bool tracked = false;
  double confidence = 0;
};

/// One row of a ground-truth CSV; only frame, x, y, z and visible are required columns.
struct TruthRow {
  std::uint64_t frame = 0;
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool visible = false;
};

/// Writes one hand row (no header) to `out`.
void write_hand_row(std::ostream& out, std::uint64_t frame, std::int64_t stamp_ns, const HandObservation& hand);

/// Read a CSV by column name. Throw std::runtime_error naming the file, the line and the column.
std::vector<HandRow> read_hand_csv(const std::filesystem::path& file);
std::vector<TruthRow> read_truth_csv(const std::filesystem::path& file);

struct Evaluation {
  std::size_t truth_frames = 0;     ///< rows in the ground truth
  std::size_t missing_frames = 0;   ///< ground-truth frames with no hand row
  std::size_t visible = 0;          ///< frames where the hand is visible
  std::size_t tracked_visible = 0;  ///< ... and tracked
  std::size_t phantoms = 0;         ///< tracked while not visible
  double tracked_ratio = 0;         ///< tracked_visible / visible (1 when nothing is visible)
  double rms_m = 0;                 ///< RMS 3D error over tracked visible frames
  double median_m = 0;
  double max_m = 0;
};

/// Joins hands and truth by frame number.
Evaluation evaluate(const std::vector<HandRow>& hands, const std::vector<TruthRow>& truth);

}  // namespace tachi::sensor
