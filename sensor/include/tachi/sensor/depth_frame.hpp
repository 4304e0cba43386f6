// One Kinect v1 depth frame as libfreenect delivers it: 640x480 raw 11-bit disparity
// (FREENECT_DEPTH_11BIT, FREENECT_RESOLUTION_MEDIUM), 2047 meaning "no reading".
#pragma once

#include <cstdint>
#include <vector>

namespace tachi::sensor {

inline constexpr int kDepthWidth = 640;
inline constexpr int kDepthHeight = 480;
inline constexpr int kDepthPixels = kDepthWidth * kDepthHeight;
inline constexpr std::uint16_t kNoReading = 2047;  ///< raw value of a pixel without a depth reading
inline constexpr std::uint16_t kMaxValidRaw = 2046;

struct DepthFrame {
  std::uint64_t frame = 0;          ///< frame number since the source started (0-based)
  std::int64_t stamp_ns = 0;        ///< host time of capture (the recording's host time during playback)
  std::uint32_t device_timestamp = 0;  ///< the Kinect's own frame timestamp
  std::vector<std::uint16_t> raw;   ///< kDepthPixels values, row-major

  std::uint16_t at(int u, int v) const { return raw[static_cast<std::size_t>(v) * kDepthWidth + u]; }
};

}  // namespace tachi::sensor
