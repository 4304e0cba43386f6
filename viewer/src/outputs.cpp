#include "tachi/viewer/outputs.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace tachi::viewer {
namespace {
// .mp4 as H.264 (what browsers and phones play) when this FFmpeg can encode it, else MPEG-4 part 2;
// .avi as Motion JPEG.
cv::VideoWriter open_video(const std::string& path, double fps, cv::Size size) {
  cv::VideoWriter writer;
  if (std::filesystem::path(path).extension() == ".avi") {
    writer.open(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size);
  } else {
    for (const auto& codec : {"avc1", "mp4v"})
      if (writer.open(path, cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]), fps, size)) break;
  }
  if (!writer.isOpened()) throw std::runtime_error("--video: cannot open " + path + " for writing");
  return writer;
}
}  // namespace

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write image " + path);
}

Outputs::Outputs(const ViewerOptions& o, cv::Size size) : options_(o) {
  if (!o.frames_dir.empty()) std::filesystem::create_directories(o.frames_dir);
  if (!o.video.empty()) video_ = open_video(o.video, o.fps, size);
  video_size_ = size;
}

void Outputs::frame(const cv::Mat& image, Clock::time_point now) {
  last_ = image;
  if (!options_.frames_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05llu.png", static_cast<unsigned long long>(frames_));
    write_image((std::filesystem::path(options_.frames_dir) / name).string(), image);
  }
  if (video_.isOpened()) {
    if (!video_start_) video_start_ = now;
    const auto due = video_frames_due(std::chrono::duration<double>(now - *video_start_).count(), options_.fps);
    if (due > video_frames_) {
      // A video keeps one frame size: a resized window is scaled to it.
      cv::Mat scaled;
      if (image.size() != video_size_) cv::resize(image, scaled, video_size_, 0, 0, cv::INTER_AREA);
      const cv::Mat& written = scaled.empty() ? image : scaled;
      for (; video_frames_ < due; ++video_frames_) video_.write(written);
    }
  }
  ++frames_;
}

void Outputs::snapshot_now() {
  if (last_.empty()) return;
  std::filesystem::create_directories(options_.snapshot_dir);
  const auto path = std::filesystem::path(options_.snapshot_dir) / ("tachi_snapshot_" + std::to_string(++snapshots_) + ".png");
  write_image(path.string(), last_);
  spdlog::info("tachi-viewer: snapshot saved to {}", path.string());
}

void Outputs::finish(const cv::Mat& last) {
  if (!options_.snapshot.empty()) write_image(options_.snapshot, last);
  if (video_.isOpened()) {
    video_.release();
    spdlog::info("tachi-viewer: {} frames rendered, {} video frames at {} fps written to {}", frames_, video_frames_,
                 options_.fps, options_.video);
  }
}

}  // namespace tachi::viewer
