#include "tachi/sensor/depth_source.hpp"

#include "tachi/common/app.hpp"

#include <algorithm>

namespace tachi::sensor {

RecordingSource::RecordingSource(const std::filesystem::path& dir, Playback playback)
    : dir_(dir), playback_(playback), model_(model_for_recording(dir)) {
  if (playback_.rate < 0.0) throw RecordingError("recording " + dir.string() + ": playback rate must be >= 0");
  for (auto& e : read_index(dir))
    if (e.kind == EntryKind::Depth) depth_entries_.push_back(std::move(e));
  for (const auto& e : depth_entries_) depth_files_.push_back(dir_ / e.file);
}

std::optional<DepthFrame> RecordingSource::next() {
  DepthFrame frame;
  if (!next_into(frame)) return std::nullopt;
  return frame;
}

bool RecordingSource::next_into(DepthFrame& frame) {
  if (position_ == depth_entries_.size()) {
    if (!playback_.loop) return false;
    // Keep the timeline monotonic across loops: the next pass starts one frame period later.
    const auto& first = depth_entries_.front();
    const auto& last = depth_entries_.back();
    const std::int64_t period = depth_entries_.size() > 1
                                    ? (last.host_time_ns - first.host_time_ns) / static_cast<std::int64_t>(depth_entries_.size() - 1)
                                    : 33'333'333;
    loop_offset_ns_ += last.host_time_ns - first.host_time_ns + period;
    position_ = 0;
  }
  const IndexEntry& e = depth_entries_[position_];
  frame.frame = frames_out_;
  frame.stamp_ns = e.host_time_ns + loop_offset_ns_;
  frame.device_timestamp = e.device_timestamp;
  frame.accel.reset();
  read_depth_file(depth_files_[position_], frame.raw, file_bytes_);

  if (playback_.rate > 0.0 && frames_out_ >= playback_.unpaced_frames) {
    const auto now = std::chrono::steady_clock::now();
    if (!start_wall_) {
      start_wall_ = now;
      start_host_ns_ = frame.stamp_ns;
    } else {
      // In double seconds, capped: a host time that jumps by hours, or --rate 1e-9, must not overflow
      // the clock. The wait ends at SIGINT/SIGTERM (the stream then ends here).
      const double wait_s = static_cast<double>(frame.stamp_ns - start_host_ns_) * 1e-9 / playback_.rate;
      const auto due = *start_wall_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                          std::chrono::duration<double>(std::min(wait_s, 1e9)));
      if (due > now && !common::sleep_unless_stopped(due)) return false;
    }
  }
  ++position_;
  ++frames_out_;
  return true;
}

}  // namespace tachi::sensor
