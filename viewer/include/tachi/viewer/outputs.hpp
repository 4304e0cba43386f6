// Everything that turns the viewer's frames into files: --video, --frames-dir, --snapshot and the `p` key.
#pragma once

#include "tachi/viewer/live_policies.hpp"
#include "tachi/viewer/options.hpp"
#include "tachi/viewer/video_writer.hpp"

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <optional>
#include <string>

namespace tachi::viewer {

/// Writes `image` to `path` (PNG by its extension); throws naming the path when it cannot.
void write_image(const std::string& path, const cv::Mat& image);

class Outputs {
 public:
  /// Opens --video at `size` and creates --frames-dir; throws naming the flag when it cannot.
  Outputs(const ViewerOptions& o, cv::Size size);
  /// One rendered frame, shown at `now`. The video's time stamps are its frame numbers over --fps, so
  /// a frame is written as many times as --fps frames fit since the first one (video_frames_due).
  /// Throws common::DiskFull naming the file when a file's filesystem is full.
  void frame(const cv::Mat& image, Clock::time_point now);
  /// The `p` key: the last frame as snapshot_dir/tachi_snapshot_N.png.
  void snapshot_now();
  /// --snapshot of `last`, and the video closed. Throws like frame() when the video cannot be finished.
  void finish(const cv::Mat& last);
  /// Whether any output flag was given (headless without one writes nothing).
  [[nodiscard]] bool any() const { return !options_.snapshot.empty() || !options_.frames_dir.empty() || !options_.video.empty(); }

 private:
  bool video_open() const { return mp4_.has_value() || avi_.isOpened(); }

  const ViewerOptions& options_;
  std::optional<FragmentedMp4Writer> mp4_;  // .mp4: fragmented, playable up to a kill (video_writer.hpp)
  cv::VideoWriter avi_;                     // .avi: OpenCV's Motion JPEG
  cv::Size video_size_;
  cv::Mat last_;
  std::uint64_t frames_ = 0;
  std::optional<Clock::time_point> video_start_;
  std::uint64_t video_frames_ = 0;
  unsigned snapshots_ = 0;
};

}  // namespace tachi::viewer
