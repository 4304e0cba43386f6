// The .mp4 of --video: fragmented MP4 written with FFmpeg's libraries (libavformat, libavcodec,
// libswscale) directly.
//
// Why not cv::VideoWriter: OpenCV 4.6 opens the MP4 muxer with no options (avformat_write_header(oc,
// NULL)), so the muxer keeps an index entry of every frame in memory until the file is closed (the
// viewer grew ~110 KB a minute in a one-hour soak) and writes that index, the moov atom, only at the
// close: a viewer killed before it (SIGKILL, the launcher's death, a power loss) left a video that does not
// play at all. Here the muxer writes fragmented MP4 (movflags frag_keyframe+empty_moov+default_base_moof)
// with a keyframe every second: each fragment carries its own index and the muxer drops it once written
// (it keeps one 40-byte entry per fragment: ~4 KB a minute instead of ~130 KB, docs/viewer.md), and a
// video cut short plays up to its last whole fragment.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <string>

namespace tachi::viewer {

class FragmentedMp4Writer {
 public:
  /// Opens `path` for BGR frames (CV_8UC3) of `size` at `fps` frames a second: H.264 (libx264, what
  /// browsers and phones play) when this FFmpeg has the encoder, else MPEG-4 part 2. 4:2:0 video needs
  /// even sides, so an odd width or height loses its last column or row. Throws std::runtime_error
  /// "cannot open PATH for writing: REASON", or common::DiskFull when not even the header fits.
  FragmentedMp4Writer(const std::string& path, double fps, cv::Size size);
  /// Finishes the video if finish() was not called; a failure here is logged, not thrown.
  ~FragmentedMp4Writer();
  FragmentedMp4Writer(FragmentedMp4Writer&&) noexcept;
  FragmentedMp4Writer& operator=(FragmentedMp4Writer&&) noexcept;
  FragmentedMp4Writer(const FragmentedMp4Writer&) = delete;
  FragmentedMp4Writer& operator=(const FragmentedMp4Writer&) = delete;

  /// Appends one frame (its time stamp is its number over fps). `bgr` must have the size given at
  /// opening. Throws common::DiskFull when the file's filesystem is full, else std::runtime_error
  /// naming the file; after a throw the writer writes nothing more.
  void write(const cv::Mat& bgr);
  /// Drains the encoder, writes the last fragment and closes the file. Throws like write(); a second
  /// call does nothing.
  void finish();

  /// "libx264" or "mpeg4".
  [[nodiscard]] std::string codec() const;
  /// The encoded frame size (the opening size, made even).
  [[nodiscard]] cv::Size frame_size() const;
  [[nodiscard]] std::uint64_t frames_written() const;

 private:
  struct Muxer;  // FFmpeg's contexts, kept out of this header
  std::unique_ptr<Muxer> muxer_;
};

}  // namespace tachi::viewer
