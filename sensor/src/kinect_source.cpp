#include "tachi/sensor/kinect_source.hpp"

#include <libfreenect.h>

#include <chrono>
#include <cstring>
#include <string>

namespace tachi::sensor {

struct KinectSource::Device {
  freenect_context* ctx = nullptr;
  freenect_device* dev = nullptr;
  bool depth_started = false;
  bool ready = false;  // a frame arrived since the last next()
  DepthFrame frame;
  std::uint64_t count = 0;

  static void on_depth(freenect_device* dev, void* data, std::uint32_t timestamp) {
    auto* self = static_cast<Device*>(freenect_get_user(dev));
    self->frame.frame = self->count++;
    self->frame.stamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
    self->frame.device_timestamp = timestamp;
    self->frame.raw.resize(kDepthPixels);
    std::memcpy(self->frame.raw.data(), data, static_cast<std::size_t>(kDepthPixels) * sizeof(std::uint16_t));
    self->ready = true;
  }

  ~Device() {
    if (dev) {
      if (depth_started) freenect_stop_depth(dev);
      freenect_close_device(dev);
    }
    if (ctx) freenect_shutdown(ctx);
  }
};

KinectSource::KinectSource(int index, DepthModel model, std::function<bool()> stop)
    : device_(std::make_unique<Device>()), model_(model), stop_(std::move(stop)) {
  Device& d = *device_;
  if (freenect_init(&d.ctx, nullptr) < 0) {
    d.ctx = nullptr;
    throw NoKinectError();  // libusb could not start: no device we can reach
  }
  freenect_set_log_level(d.ctx, FREENECT_LOG_ERROR);
  freenect_select_subdevices(d.ctx, FREENECT_DEVICE_CAMERA);
  const int devices = freenect_num_devices(d.ctx);
  if (devices <= 0) throw NoKinectError();
  if (index < 0 || index >= devices)
    throw std::runtime_error("Kinect #" + std::to_string(index) + " requested but " + std::to_string(devices) + " found");
  if (freenect_open_device(d.ctx, &d.dev, index) < 0) {
    d.dev = nullptr;
    throw std::runtime_error("freenect_open_device(" + std::to_string(index) + ") failed (permissions on the USB device?)");
  }
  freenect_set_user(d.dev, &d);
  freenect_set_depth_callback(d.dev, &Device::on_depth);
  const freenect_frame_mode mode = freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT);
  if (!mode.is_valid || freenect_set_depth_mode(d.dev, mode) < 0)
    throw std::runtime_error("freenect_set_depth_mode(MEDIUM, 11BIT) failed");
  if (freenect_start_depth(d.dev) < 0) throw std::runtime_error("freenect_start_depth failed");
  d.depth_started = true;
}

KinectSource::~KinectSource() = default;

std::optional<DepthFrame> KinectSource::next() {
  Device& d = *device_;
  d.ready = false;
  while (!d.ready) {
    if (stop_ && stop_()) return std::nullopt;
    timeval timeout{0, 200'000};
    // < 0: a USB error on a device, or the end of a fakenect recording: the stream is over.
    if (freenect_process_events_timeout(d.ctx, &timeout) < 0) return std::nullopt;
  }
  return std::move(d.frame);
}

}  // namespace tachi::sensor
