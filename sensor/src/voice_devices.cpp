// Live microphones: ALSA through sphinxad, the Kinect's array through libfreenect_audio.
// C error codes become exceptions here; "no device" is its own exception so main can say so plainly.
#include "tachi/sensor/voice_audio.hpp"

#include <libfreenect.h>
#include <libfreenect_audio.h>
#include <sphinxbase/ad.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <mutex>
#include <thread>

namespace tachi::sensor {

namespace {

class AlsaSource : public AudioSource {
 public:
  explicit AlsaSource(const std::string& device) : name_(device.empty() ? "default" : device) {
    ad_ = ad_open_dev(device.empty() ? nullptr : device.c_str(), kVoiceSampleRate);
    if (ad_ == nullptr)
      throw AudioDeviceNotFound("cannot open audio capture device '" + name_ +
                                "' at 16 kHz (no sound card, or wrong --device name; `arecord -L` lists them)");
    if (ad_start_rec(ad_) < 0) {
      ad_close(ad_);
      throw std::runtime_error("cannot start recording on audio device '" + name_ + "'");
    }
  }
  ~AlsaSource() override {
    ad_stop_rec(ad_);
    ad_close(ad_);
  }
  AlsaSource(const AlsaSource&) = delete;
  AlsaSource& operator=(const AlsaSource&) = delete;

  long read(std::span<std::int16_t> buffer) override {
    const int32 n = ad_read(ad_, buffer.data(), static_cast<int32>(buffer.size()));
    if (n < 0) throw std::runtime_error("reading audio device '" + name_ + "' failed (device unplugged?)");
    if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return n;
  }

 private:
  std::string name_;
  ad_rec_t* ad_ = nullptr;
};

class KinectMicSource : public AudioSource {
 public:
  explicit KinectMicSource(int index) {
    if (freenect_init(&ctx_, nullptr) < 0) throw AudioDeviceNotFound("libfreenect could not start (no USB access?)");
    freenect_set_log_level(ctx_, FREENECT_LOG_FATAL);
    freenect_select_subdevices(ctx_, FREENECT_DEVICE_AUDIO);
    const int count = freenect_num_devices(ctx_);
    if (count <= index) {
      freenect_shutdown(ctx_);
      throw AudioDeviceNotFound("no Kinect found for its microphones (" + std::to_string(count < 0 ? 0 : count) +
                                " attached); use --wav FILE or --device NAME");
    }
    if (freenect_open_device(ctx_, &dev_, index) < 0) {
      freenect_shutdown(ctx_);
      throw AudioDeviceNotFound("cannot open the Kinect's audio subdevice " + std::to_string(index) +
                                " (Kinect model 1414 needs its audio firmware; permissions?)");
    }
    freenect_set_user(dev_, this);
    freenect_set_audio_in_callback(dev_, &KinectMicSource::on_audio);
    if (freenect_start_audio(dev_) < 0) {
      freenect_close_device(dev_);
      freenect_shutdown(ctx_);
      throw std::runtime_error("cannot start the Kinect's audio stream");
    }
  }
  ~KinectMicSource() override {
    freenect_stop_audio(dev_);
    freenect_close_device(dev_);
    freenect_shutdown(ctx_);
  }
  KinectMicSource(const KinectMicSource&) = delete;
  KinectMicSource& operator=(const KinectMicSource&) = delete;

  long read(std::span<std::int16_t> buffer) override {
    if (freenect_process_events(ctx_) < 0) throw std::runtime_error("Kinect audio stream failed (unplugged?)");
    std::lock_guard lock(mutex_);
    const std::size_t n = std::min(buffer.size(), pending_.size());
    std::copy_n(pending_.begin(), n, buffer.begin());
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
    return static_cast<long>(n);
  }

 private:
  // The echo-cancelled channel is the one the Kinect's own speech recognition uses: 16 kHz, 16-bit.
  static void on_audio(freenect_device* dev, int num_samples, int32_t*, int32_t*, int32_t*, int32_t*, int16_t* cancelled,
                       void*) {
    auto* self = static_cast<KinectMicSource*>(freenect_get_user(dev));
    std::lock_guard lock(self->mutex_);
    self->pending_.insert(self->pending_.end(), cancelled, cancelled + num_samples);
  }

  freenect_context* ctx_ = nullptr;
  freenect_device* dev_ = nullptr;
  std::mutex mutex_;
  std::deque<std::int16_t> pending_;
};

}  // namespace

std::unique_ptr<AudioSource> open_alsa_source(const std::string& device) { return std::make_unique<AlsaSource>(device); }

std::unique_ptr<AudioSource> open_kinect_mic_source(int device_index) {
  return std::make_unique<KinectMicSource>(device_index);
}

}  // namespace tachi::sensor
