// The live Kinect v1 through libfreenect's async API: 11-bit depth, FREENECT_RESOLUTION_MEDIUM.
// Works unchanged on libfreenect's fakenect build (LD_LIBRARY_PATH=<libdir>/fakenect,
// FAKENECT_PATH=<recording>, FAKENECT_LOOP=0), which serves a recording through the same API and
// returns an error from freenect_process_events at its end: that is the end of the stream here.
// (Its sync wrapper hangs at the end of a recording, hence the async API.)
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>

#include "tachi/sensor/depth_source.hpp"

namespace tachi::sensor {

/// No device (or no USB access): main turns this into exit code 3.
class NoKinectError : public std::runtime_error {
 public:
  NoKinectError() : std::runtime_error("no Kinect found; use --recording DIR") {}
};

class KinectSource final : public DepthSource {
 public:
  /// Opens device `index`; throws NoKinectError when there is none, std::runtime_error on a
  /// libfreenect failure. `stop` is polled while waiting for a frame.
  explicit KinectSource(int index = 0, DepthModel model = {}, std::function<bool()> stop = {});
  ~KinectSource() override;
  KinectSource(const KinectSource&) = delete;
  KinectSource& operator=(const KinectSource&) = delete;

  std::optional<DepthFrame> next() override;
  const DepthModel& model() const override { return model_; }

 private:
  struct Device;
  std::unique_ptr<Device> device_;
  DepthModel model_;
  std::function<bool()> stop_;
};

}  // namespace tachi::sensor
