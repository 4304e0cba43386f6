// One Kinect v1 depth frame as libfreenect delivers it: 640x480 raw 11-bit disparity
// (FREENECT_DEPTH_11BIT, FREENECT_RESOLUTION_MEDIUM), 2047 meaning "no reading".
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace tachi::sensor {

inline constexpr int kDepthWidth = 640;
inline constexpr int kDepthHeight = 480;
inline constexpr int kDepthPixels = kDepthWidth * kDepthHeight;
inline constexpr std::uint16_t kNoReading = 2047;  ///< raw value of a pixel without a depth reading
inline constexpr std::uint16_t kMaxValidRaw = 2046;

/// Kinect accelerometer sample (freenect_raw_tilt_state). 819 counts per g.
struct AccelSample {
  std::int16_t ax = 0;
  std::int16_t ay = 819;  ///< sensor upright: gravity along +y
  std::int16_t az = 0;
  std::int8_t tilt_angle = 0;  ///< half degrees
  std::int32_t tilt_status = 0;
};

struct DepthFrame {
  std::uint64_t frame = 0;          ///< frame number since the source started (0-based)
  std::int64_t stamp_ns = 0;        ///< host time of capture (the recording's host time during playback)
  std::uint32_t device_timestamp = 0;  ///< the Kinect's own frame timestamp
  std::vector<std::uint16_t> raw;   ///< kDepthPixels values, row-major
  /// The accelerometer at capture, when the source reads it. Neither the live source (it opens the
  /// camera subdevice only) nor recording playback fills it yet, so --record writes no a-*.dump
  /// entries rather than invented ones.
  std::optional<AccelSample> accel;

  std::uint16_t at(int u, int v) const { return raw[static_cast<std::size_t>(v) * kDepthWidth + u]; }
};

}  // namespace tachi::sensor
