#include "tachi/viewer/outputs.hpp"

#include "tachi/common/disk_full.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace tachi::viewer {
namespace {
// .avi as Motion JPEG through OpenCV; .mp4 goes through FragmentedMp4Writer (see there why not OpenCV).
cv::VideoWriter open_avi(const std::string& path, double fps, cv::Size size) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size);
  if (!writer.isOpened()) throw std::runtime_error("--video: cannot open " + path + " for writing");
  return writer;
}
}  // namespace

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write image " + path);
}

Outputs::Outputs(const ViewerOptions& o, cv::Size size) : options_(o) {
  if (!o.frames_dir.empty()) std::filesystem::create_directories(o.frames_dir);
  if (std::filesystem::path(o.video).extension() == ".avi") {
    avi_ = open_avi(o.video, o.fps, size);
  } else if (!o.video.empty()) {
    try {
      mp4_.emplace(o.video, o.fps, size);
    } catch (const common::DiskFull&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string("--video: ") + e.what());
    }
  }
  video_size_ = size;
}

void Outputs::frame(const cv::Mat& image, Clock::time_point now) {
  last_ = image;
  if (!options_.frames_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05llu.png", static_cast<unsigned long long>(frames_));
    write_image((std::filesystem::path(options_.frames_dir) / name).string(), image);
  }
  if (video_open()) {
    if (!video_start_) video_start_ = now;
    const auto due = video_frames_due(std::chrono::duration<double>(now - *video_start_).count(), options_.fps);
    if (due > video_frames_) {
      // A video keeps one frame size: a resized window is scaled to it.
      cv::Mat scaled;
      if (image.size() != video_size_) cv::resize(image, scaled, video_size_, 0, 0, cv::INTER_AREA);
      const cv::Mat& written = scaled.empty() ? image : scaled;
      for (; video_frames_ < due; ++video_frames_) {
        if (mp4_)
          mp4_->write(written);
        else
          avi_.write(written);
      }
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
  if (video_open()) {
    if (mp4_) mp4_->finish();
    mp4_.reset();
    avi_.release();
    spdlog::info("tachi-viewer: {} frames rendered, {} video frames at {} fps written to {}", frames_, video_frames_,
                 options_.fps, options_.video);
  }
}

}  // namespace tachi::viewer
