// The viewer draws the object's points: tachi-sim live with a PLY table under the cloth and
// a headless tachi-viewer on the same domain (202): the viewer's snapshot shows the table's dots in
// the object colour, where a run without an object shows none. Domain ids 202-203 belong to this file.
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "table_ply.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <functional>
#include <future>


namespace {

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

// viewer/src/render.cpp draws object points as filled dots of this BGR colour (no anti-aliasing).
const cv::Vec3b kObjectColour{80, 220, 240};

int object_pixels(const std::string& png) {
  const cv::Mat image = cv::imread(png, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty()) << png;
  int n = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) n += image.at<cv::Vec3b>(y, x) == kObjectColour ? 1 : 0;
  return n;
}

// The simulator (with `object_args`) and a viewer run together for a few seconds; the viewer's last frame.
int object_pixels_of_run(const tachi::test::ScratchDir& dir, unsigned domain, std::vector<std::string> object_args) {
  const std::string d = std::to_string(domain);
  const std::string png = (dir / ("view" + d + ".png")).string();
  std::vector<std::string> sim{tachi::test::executable("tachi-sim"), "--grid", "16", "--pin", "top-edge", "--domain", d, "--duration", "3"};
  sim.insert(sim.end(), object_args.begin(), object_args.end());
  ChildProcess simulator(sim);
  ChildProcess viewer({tachi::test::executable("tachi-viewer"), "--headless", "--domain", d, "--snapshot", png, "--size", "320", "--exit-when-idle", "1"});
  EXPECT_EQ(simulator.wait(30s), 0) << simulator.err();
  EXPECT_EQ(viewer.wait(30s), 0) << viewer.err();
  return object_pixels(png);
}

TEST(ObjectView, TheViewerDrawsTheObjectsPoints) {
  const tachi::test::ScratchDir dir{"object_view"};
  // A 1.2 m square table of points, 4 cm apart, 0.7 m below the cloth's centre, turned flat.
  tachi::test::write_table_ply(dir / "table.ply", 15, 0.04);
  // Both runs side by side, on their own domains (each mostly waits out its --duration).
  auto without_run = std::async(std::launch::async, object_pixels_of_run, std::cref(dir), 203u, std::vector<std::string>{});
  const int with = object_pixels_of_run(dir, 202, {"--object", (dir / "table.ply").string(), "--object-pose", "0,-0.7,0,90,0,0"});
  const int without = without_run.get();
  EXPECT_EQ(without, 0) << "nothing else is drawn in the object colour";
  EXPECT_GT(with, 200) << "the table's dots (961 points, some behind the cloth)";
}

}  // namespace
