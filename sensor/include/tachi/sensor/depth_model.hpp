// Kinect v1 depth model: raw disparity -> metres (Burrus' fit) and the pinhole model of the
// depth camera. Defaults are Nicolas Burrus' widely used calibration of a Kinect v1
// (http://nicolas.burrus.name/index.php/Research/KinectCalibration); a calibration.json next to a
// recording overrides them.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <Eigen/Core>

namespace tachi::sensor {

struct Intrinsics {
  double fx = 594.214;
  double fy = 591.040;
  double cx = 339.308;
  double cy = 242.739;
};

/// z = 1 / (raw * a + b): Burrus' disparity fit; a, b in 1/m.
struct DisparityFit {
  double a = -0.0030711016;
  double b = 3.3309495161;
};

/// Raw disparity <-> metres and pixel <-> camera frame (x right, y down, z forward, metres).
class DepthModel {
 public:
  DepthModel() : DepthModel(Intrinsics{}, DisparityFit{}) {}
  DepthModel(const Intrinsics& intrinsics, const DisparityFit& fit);

  const Intrinsics& intrinsics() const noexcept { return intrinsics_; }
  const DisparityFit& fit() const noexcept { return fit_; }

  /// Metres for a raw value: a 2048-entry table; 0 for 2047 (no reading) and for raw values the
  /// fit maps to no positive depth.
  float metres(std::uint16_t raw) const noexcept { return table_[raw & 2047u]; }
  const std::array<float, 2048>& table() const noexcept { return table_; }

  /// Inverse of the fit: the (real-valued) raw disparity at depth z (used to render and to turn
  /// metric thresholds into raw thresholds).
  double raw_at(double z_m) const noexcept { return (1.0 / z_m - fit_.b) / fit_.a; }

  /// Pinhole back-projection of pixel (u, v) at depth z.
  Eigen::Vector3d back_project(double u, double v, double z) const noexcept {
    return {(u - intrinsics_.cx) * z / intrinsics_.fx, (v - intrinsics_.cy) * z / intrinsics_.fy, z};
  }
  /// Pinhole projection; requires p.z() > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const noexcept {
    return {intrinsics_.cx + intrinsics_.fx * p.x() / p.z(), intrinsics_.cy + intrinsics_.fy * p.y() / p.z()};
  }

 private:
  Intrinsics intrinsics_;
  DisparityFit fit_;
  std::array<float, 2048> table_{};
};

/// Name of the optional calibration file in a recording's folder.
inline constexpr const char* kCalibrationFile = "calibration.json";

/// Reads a calibration file: {"fx":..,"fy":..,"cx":..,"cy":..,"disparity_a":..,"disparity_b":..};
/// missing keys keep their defaults. Throws std::runtime_error naming the file and the key on a bad
/// file or a non-positive focal length.
DepthModel load_calibration(const std::filesystem::path& file);

/// The model for a recording: its calibration.json when present, else the defaults.
DepthModel model_for_recording(const std::filesystem::path& recording_dir);

/// Writes a calibration file readable by load_calibration.
void save_calibration(const std::filesystem::path& file, const DepthModel& model);

}  // namespace tachi::sensor
