// The live source through the real libfreenect API, served by libfreenect's fakenect build
// (ctest sets LD_LIBRARY_PATH to it and FAKENECT_LOOP=0; each test sets FAKENECT_PATH).
#include "tachi/sensor/kinect_source.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/hand_finder.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

void use_fakenect(const std::filesystem::path& recording) {
  const char* path = std::getenv("LD_LIBRARY_PATH");
  ASSERT_TRUE(path && std::string(path).find("fakenect") != std::string::npos)
      << "run through ctest, or with LD_LIBRARY_PATH=/usr/lib/<arch>/fakenect FAKENECT_LOOP=0";
  ::setenv("FAKENECT_PATH", recording.c_str(), 1);
}

TEST(KinectSource, FakenectServesTheSameHandsAsTheRecordingReader) {
  const auto dir = std::filesystem::path(test::recordings_dir()) / "jitter";
  use_fakenect(dir);
  KinectSource live;
  RecordingSource recording(dir, Playback{0.0, false});
  HandFinder live_finder(live.model()), recording_finder(recording.model());
  std::size_t frames = 0, tracked = 0;
  while (auto f = live.next()) {
    const auto g = recording.next();
    ASSERT_TRUE(g) << "live source gave more frames than the recording holds";
    EXPECT_EQ(f->frame, g->frame);
    ASSERT_EQ(f->raw, g->raw) << "frame " << f->frame;
    const auto a = live_finder.find(*f), b = recording_finder.find(*g);
    ASSERT_EQ(a.tracked, b.tracked) << "frame " << f->frame;
    EXPECT_EQ(a.position_m, b.position_m);
    ++frames;
    tracked += a.tracked;
  }
  EXPECT_FALSE(recording.next()) << "live source ended early";
  EXPECT_EQ(frames, recording.depth_frame_count());
  EXPECT_GT(tracked, 100u);
}

TEST(KinectSource, FakenectPlaysBackWhatOurRecorderWrote) {
  test::ScratchDir scratch("record");
  const auto out = scratch.path() / "rec";
  std::vector<DepthFrame> written;
  {
    RecordingSource source(std::filesystem::path(test::recordings_dir()) / "push", Playback{0.0, false});
    FakenectWriter writer(out);
    for (int i = 0; i < 20; ++i) {
      auto f = source.next();
      ASSERT_TRUE(f);
      writer.write_depth(*f);
      writer.write_accel(f->stamp_ns, f->device_timestamp, AccelSample{});
      written.push_back(std::move(*f));
    }
  }
  use_fakenect(out);
  KinectSource live;
  std::size_t i = 0;
  while (auto f = live.next()) {
    ASSERT_LT(i, written.size());
    EXPECT_EQ(f->raw, written[i].raw) << "frame " << i;
    EXPECT_EQ(f->device_timestamp, written[i].device_timestamp);
    ++i;
  }
  EXPECT_EQ(i, written.size());
}

}  // namespace
}  // namespace tachi::sensor
