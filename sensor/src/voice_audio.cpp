#include "tachi/sensor/voice_audio.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace tachi::sensor {

namespace {
std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 | static_cast<std::uint32_t>(p[2]) << 16 |
         static_cast<std::uint32_t>(p[3]) << 24;
}
std::uint16_t le16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
}  // namespace

PcmAudio parse_wav(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 12 || std::memcmp(bytes.data(), "RIFF", 4) != 0 || std::memcmp(bytes.data() + 8, "WAVE", 4) != 0)
    throw std::runtime_error("not a RIFF/WAVE file");
  bool have_fmt = false;
  int channels = 0;
  PcmAudio audio;
  std::size_t at = 12;
  while (at + 8 <= bytes.size()) {
    const std::uint8_t* chunk = bytes.data() + at;
    const std::size_t size = le32(chunk + 4);
    const std::size_t body = at + 8;
    if (std::memcmp(chunk, "fmt ", 4) == 0) {
      if (size < 16 || body + 16 > bytes.size()) throw std::runtime_error("WAV fmt chunk is truncated");
      std::uint16_t format = le16(bytes.data() + body);
      channels = le16(bytes.data() + body + 2);
      audio.sample_rate = static_cast<int>(le32(bytes.data() + body + 4));
      const int bits = le16(bytes.data() + body + 14);
      if (format == 0xFFFE && size >= 40 && body + 26 <= bytes.size()) format = le16(bytes.data() + body + 24);
      if (format != 1) throw std::runtime_error("WAV data is not PCM (format " + std::to_string(format) + "); convert it with sox");
      if (bits != 16) throw std::runtime_error("WAV data is " + std::to_string(bits) + "-bit; 16-bit PCM is supported (sox -b 16)");
      if (channels < 1 || channels > 32) throw std::runtime_error("WAV has " + std::to_string(channels) + " channels");
      if (audio.sample_rate < 4000 || audio.sample_rate > 384000)
        throw std::runtime_error("WAV sample rate " + std::to_string(audio.sample_rate) + " Hz is out of range");
      have_fmt = true;
    } else if (std::memcmp(chunk, "data", 4) == 0) {
      if (!have_fmt) throw std::runtime_error("WAV data chunk comes before its fmt chunk");
      // A recorder killed mid-write leaves a short data chunk: read what is there.
      const std::size_t available = std::min(size, bytes.size() - body);
      const std::size_t frames = available / (2 * static_cast<std::size_t>(channels));
      audio.samples.resize(frames);
      for (std::size_t f = 0; f < frames; ++f) {
        long sum = 0;
        for (int c = 0; c < channels; ++c)
          sum += static_cast<std::int16_t>(le16(bytes.data() + body + 2 * (f * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c))));
        audio.samples[f] = static_cast<std::int16_t>(sum / channels);
      }
      return audio;
    }
    at = body + size + (size & 1U);  // chunks are padded to even sizes
  }
  throw std::runtime_error(have_fmt ? "WAV file has no data chunk" : "WAV file has no fmt chunk");
}

PcmAudio read_wav_file(const std::string& path) {
  const auto bytes = read_bytes(path);
  try {
    return parse_wav(bytes);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

PcmAudio read_raw_file(const std::string& path) {
  const auto bytes = read_bytes(path);
  PcmAudio audio;
  audio.samples.resize(bytes.size() / 2);
  for (std::size_t i = 0; i < audio.samples.size(); ++i) audio.samples[i] = static_cast<std::int16_t>(le16(bytes.data() + 2 * i));
  return audio;
}

std::vector<std::int16_t> resample_to_16k(const PcmAudio& audio) {
  if (audio.sample_rate == kVoiceSampleRate || audio.samples.empty()) return audio.samples;
  const double ratio = static_cast<double>(audio.sample_rate) / kVoiceSampleRate;  // input samples per output sample
  std::vector<double> in(audio.samples.begin(), audio.samples.end());
  if (ratio > 1.0) {
    // Box low-pass over one output period so that decimation does not fold high frequencies into speech.
    const auto width = static_cast<std::size_t>(std::ceil(ratio));
    std::vector<double> smoothed(in.size());
    double sum = 0.0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      sum += in[i];
      if (i >= width) sum -= in[i - width];
      smoothed[i] = sum / static_cast<double>(std::min(i + 1, width));
    }
    in.swap(smoothed);
  }
  const auto n = static_cast<std::size_t>(std::floor(static_cast<double>(in.size() - 1) / ratio)) + 1;
  std::vector<std::int16_t> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) * ratio;
    const auto i0 = static_cast<std::size_t>(x);
    const std::size_t i1 = std::min(i0 + 1, in.size() - 1);
    const double v = in[i0] + (in[i1] - in[i0]) * (x - static_cast<double>(i0));
    out[i] = static_cast<std::int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
  }
  return out;
}

long BufferSource::read(std::span<std::int16_t> buffer) {
  if (next_ >= samples_.size()) return -1;
  const std::size_t n = std::min(buffer.size(), samples_.size() - next_);
  std::copy_n(samples_.begin() + static_cast<std::ptrdiff_t>(next_), n, buffer.begin());
  next_ += n;
  return static_cast<long>(n);
}

}  // namespace tachi::sensor
