// Audio for the keyword spotter: 16 kHz mono signed 16-bit, the format pocketsphinx's en-us model wants.
// Sources: a WAV file (any PCM16 rate and channel count: downmixed and resampled), a raw 16 kHz file,
// an ALSA capture device (through sphinxad) or the Kinect's microphone array (through libfreenect_audio).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace tachi::sensor {

inline constexpr int kVoiceSampleRate = 16000;

/// No such capture device (no Kinect, no ALSA device of that name). main maps it to exit code 3.
class AudioDeviceNotFound : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PcmAudio {
  int sample_rate = kVoiceSampleRate;
  std::vector<std::int16_t> samples;  ///< mono
};

/// Parses a RIFF/WAVE file's bytes: PCM 16-bit (format 1 or WAVE_FORMAT_EXTENSIBLE), any channel count
/// (averaged to mono). Throws std::runtime_error saying what is wrong (not RIFF, no fmt/data chunk,
/// compressed or 8/24/32-bit data...). A data chunk cut short is read as far as it goes.
PcmAudio parse_wav(std::span<const std::uint8_t> bytes);
PcmAudio read_wav_file(const std::string& path);
/// Headerless little-endian s16 mono at 16 kHz (pocketsphinx-testdata's .raw files).
PcmAudio read_raw_file(const std::string& path);

/// Linear-interpolation resampling to 16 kHz after a box low-pass when decimating (speech survives it).
std::vector<std::int16_t> resample_to_16k(const PcmAudio& audio);

/// A stream of 16 kHz mono samples.
class AudioSource {
 public:
  virtual ~AudioSource() = default;
  /// Fills up to `buffer.size()` samples; returns how many (0 = nothing yet, keep polling), or -1 at the end.
  virtual long read(std::span<std::int16_t> buffer) = 0;
};

/// Plays a buffer of samples (a file) as fast as it is read.
class BufferSource : public AudioSource {
 public:
  explicit BufferSource(std::vector<std::int16_t> samples) : samples_(std::move(samples)) {}
  long read(std::span<std::int16_t> buffer) override;

 private:
  std::vector<std::int16_t> samples_;
  std::size_t next_ = 0;
};

/// An ALSA capture device through sphinxad. `device` empty = the default device.
/// Throws AudioDeviceNotFound when it cannot be opened.
std::unique_ptr<AudioSource> open_alsa_source(const std::string& device);

/// The Kinect v1's microphone array through libfreenect (its echo-cancelled 16 kHz channel).
/// Throws AudioDeviceNotFound when no Kinect (audio subdevice) is attached.
std::unique_ptr<AudioSource> open_kinect_mic_source(int device_index);

}  // namespace tachi::sensor
