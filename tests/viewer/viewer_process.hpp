// What the process tests of tachi-viewer share: the executables, and what they need to know about
// the default view to find things in its images (the renderer's own projection and background).
#pragma once

#include "paths.hpp"
#include "tachi/viewer/render.hpp"

#include <string>

inline const std::string kViewer = tachi::test::executable("tachi-viewer");
inline const std::string kSim = tachi::test::executable("tachi-sim");

/// Where world (x, y, 0) lands in the viewer's default view drawn at size x size.
inline cv::Point2f pixel_of(float x, float y, int size) {
  tachi::viewer::View view;
  view.width = view.height = size;
  return tachi::viewer::to_pixel(view, {x, y, 0.0f});
}

inline cv::Vec3b background_pixel() {
  const cv::Scalar& c = tachi::viewer::kBackground;
  return {static_cast<uchar>(c[0]), static_cast<uchar>(c[1]), static_cast<uchar>(c[2])};
}
