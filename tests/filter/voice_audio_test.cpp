#include "tachi/sensor/voice_audio.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace tachi::sensor {
namespace {

void put16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
  b.push_back(static_cast<std::uint8_t>(v >> 8));
}
void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  put16(b, static_cast<std::uint16_t>(v & 0xFFFF));
  put16(b, static_cast<std::uint16_t>(v >> 16));
}
// A loop, not insert(): GCC 12 warns falsely (-Wstringop-overflow) on inserting into an empty vector.
void tag(std::vector<std::uint8_t>& b, const char* t) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(t[i]));
}

std::vector<std::uint8_t> wav(int rate, int channels, int bits, const std::vector<std::int16_t>& interleaved,
                              std::uint16_t format = 1, bool extra_chunk = false) {
  std::vector<std::uint8_t> b;
  tag(b, "RIFF");
  put32(b, 0);  // size unchecked, as many writers leave it wrong
  tag(b, "WAVE");
  if (extra_chunk) {  // an odd-sized chunk before fmt: readers must skip it with its pad byte
    tag(b, "LIST");
    put32(b, 3);
    b.insert(b.end(), {'a', 'b', 'c', 0});
  }
  tag(b, "fmt ");
  put32(b, 16);
  put16(b, format);
  put16(b, static_cast<std::uint16_t>(channels));
  put32(b, static_cast<std::uint32_t>(rate));
  put32(b, static_cast<std::uint32_t>(rate * channels * bits / 8));
  put16(b, static_cast<std::uint16_t>(channels * bits / 8));
  put16(b, static_cast<std::uint16_t>(bits));
  tag(b, "data");
  put32(b, static_cast<std::uint32_t>(interleaved.size() * 2));
  for (auto s : interleaved) put16(b, static_cast<std::uint16_t>(s));
  return b;
}

TEST(VoiceAudio, ParsesMonoPcm16) {
  const auto bytes = wav(16000, 1, 16, {1, -2, 300, -32768}, 1, true);
  const PcmAudio a = parse_wav(bytes);
  EXPECT_EQ(a.sample_rate, 16000);
  EXPECT_EQ(a.samples, (std::vector<std::int16_t>{1, -2, 300, -32768}));
}

TEST(VoiceAudio, DownmixesChannels) {
  const PcmAudio a = parse_wav(wav(48000, 2, 16, {100, 300, -10, -30}));
  EXPECT_EQ(a.sample_rate, 48000);
  EXPECT_EQ(a.samples, (std::vector<std::int16_t>{200, -20}));
}

TEST(VoiceAudio, RejectsWhatItCannotReadWithAReason) {
  const auto message = [](const std::vector<std::uint8_t>& bytes) -> std::string {
    try {
      parse_wav(bytes);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message({'n', 'o', 'p', 'e'}).find("RIFF"), std::string::npos);
  EXPECT_NE(message(wav(16000, 1, 8, {})).find("8-bit"), std::string::npos);
  EXPECT_NE(message(wav(16000, 1, 16, {}, 3)).find("not PCM"), std::string::npos);
  auto no_data = wav(16000, 1, 16, {});
  no_data.resize(no_data.size() - 8);  // drop the data chunk header
  EXPECT_NE(message(no_data).find("no data chunk"), std::string::npos);
  auto short_fmt = wav(16000, 1, 16, {});
  short_fmt.resize(24);
  EXPECT_NE(message(short_fmt).find("fmt"), std::string::npos);
}

TEST(VoiceAudio, ReadsATruncatedDataChunkAsFarAsItGoes) {
  auto bytes = wav(16000, 1, 16, {1, 2, 3, 4});
  bytes.resize(bytes.size() - 3);  // 2.5 samples left
  EXPECT_EQ(parse_wav(bytes).samples, (std::vector<std::int16_t>{1, 2}));
}

TEST(VoiceAudio, ResamplesA48kToneTo16kKeepingItsFrequency) {
  PcmAudio a;
  a.sample_rate = 48000;
  for (int i = 0; i < 48000; ++i)
    a.samples.push_back(static_cast<std::int16_t>(10000 * std::sin(2 * std::numbers::pi * 440.0 * i / 48000.0)));
  const auto out = resample_to_16k(a);
  ASSERT_NEAR(static_cast<double>(out.size()), 16000.0, 1.0);
  // Zero crossings of a 440 Hz tone over 1 s: 880.
  int crossings = 0;
  for (std::size_t i = 1; i < out.size(); ++i) crossings += (out[i - 1] < 0) != (out[i] < 0) ? 1 : 0;
  EXPECT_NEAR(crossings, 880, 4);
}

TEST(VoiceAudio, BufferSourceEndsWithMinusOne) {
  BufferSource s{{1, 2, 3}};
  std::vector<std::int16_t> buf(2);
  EXPECT_EQ(s.read(buf), 2);
  EXPECT_EQ(s.read(buf), 1);
  EXPECT_EQ(s.read(buf), -1);
}

TEST(VoiceAudio, MissingDevicesFailCleanly) {
  // No sound card and no Kinect on the build machine: both must say so, not crash or hang.
  EXPECT_THROW(open_alsa_source("tachi_no_such_device"), AudioDeviceNotFound);
  EXPECT_THROW(open_kinect_mic_source(15), AudioDeviceNotFound);
}

}  // namespace
}  // namespace tachi::sensor
