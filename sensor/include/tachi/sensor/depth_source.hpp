// Where depth frames come from: one interface, implemented by a recording reader (fakenect
// format, below) and by the live Kinect (kinect_source.hpp, library tachi_sensor_kinect), so the
// rest of the pipeline cannot tell a replay from a device (as libfreenect's fakenect does).
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <vector>

#include "tachi/sensor/depth_frame.hpp"
#include "tachi/sensor/depth_model.hpp"
#include "tachi/sensor/fakenect_recording.hpp"

namespace tachi::sensor {

class DepthSource {
 public:
  virtual ~DepthSource() = default;
  /// The next depth frame; nullopt at the end of the stream. Throws on a device or file error.
  virtual std::optional<DepthFrame> next() = 0;
  /// The next depth frame into `frame`, reusing its buffer where the source can (a recording
  /// allocates nothing per frame then); false at the end of the stream.
  virtual bool next_into(DepthFrame& frame) {
    auto f = next();
    if (!f) return false;
    frame = std::move(*f);
    return true;
  }
  /// Depth conversion and intrinsics for this source's frames.
  virtual const DepthModel& model() const = 0;
};

/// How a recording is paced: real time (1.0), a factor of it, or as fast as possible (0 = max).
struct Playback {
  double rate = 1.0;
  bool loop = false;
  /// The first this many frames go out as fast as possible and pacing starts after them: a sensor
  /// resuming a killed one's playback (PlaybackProgress) catches up to where it stopped.
  std::uint64_t unpaced_frames = 0;
};

/// Plays a fakenect recording's depth frames (colour and accelerometer entries are skipped).
/// The whole index is checked at construction; a bad frame throws RecordingError when reached.
class RecordingSource final : public DepthSource {
 public:
  explicit RecordingSource(const std::filesystem::path& dir, Playback playback = {});

  std::optional<DepthFrame> next() override;
  bool next_into(DepthFrame& frame) override;
  const DepthModel& model() const override { return model_; }
  std::size_t depth_frame_count() const noexcept { return depth_entries_.size(); }

 private:
  std::filesystem::path dir_;
  Playback playback_;
  DepthModel model_;
  std::vector<IndexEntry> depth_entries_;
  std::vector<std::filesystem::path> depth_files_;  // dir_ / entry, made once
  std::vector<char> file_bytes_;                    // read_depth_file's scratch, reused
  std::size_t position_ = 0;
  std::uint64_t frames_out_ = 0;
  std::int64_t loop_offset_ns_ = 0;
  std::optional<std::chrono::steady_clock::time_point> start_wall_;
  std::int64_t start_host_ns_ = 0;
};

}  // namespace tachi::sensor
