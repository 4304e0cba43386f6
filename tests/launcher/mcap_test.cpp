// The MCAP writer and reader (launcher/src/mcap.cpp) on their own: what the writer puts down the
// reader gets back, the checksums are the standard CRC-32, and damage is refused naming the file.
#include "scratch_dir.hpp"
#include "tachi/mcap/mcap.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace {
std::span<const std::byte> bytes_of(const std::string& s) { return {reinterpret_cast<const std::byte*>(s.data()), s.size()}; }
}  // namespace

TEST(Crc32, IsTheIeeeChecksum) {
  EXPECT_EQ(tachi::mcap::crc32(bytes_of("123456789")), 0xCBF43926u);  // the CRC-32 check value
  EXPECT_EQ(tachi::mcap::crc32(bytes_of("6789"), tachi::mcap::crc32(bytes_of("12345"))), 0xCBF43926u) << "continues";
}

TEST(Mcap, WhatIsWrittenIsReadBackInOrderAcrossChunks) {
  tachi::test::ScratchDir dir("mcap");
  const auto file = dir / "t.mcap";
  {
    tachi::mcap::Writer w(file, "", "test", 256);  // small chunks: many of them
    const auto s = w.add_schema("pkg::A", "omgidl", "module pkg { struct A { long x; }; };");
    const auto a = w.add_channel(s, "a", "cdr", {{"k", "v"}});
    const auto b = w.add_channel(s, "b", "cdr");
    for (std::uint32_t i = 0; i < 100; ++i) {
      const std::string payload = "message " + std::to_string(i);
      w.write({i % 3 == 0 ? b : a, i, 1000 + i, 900 + i, bytes_of(payload)});
    }
    w.close();
    EXPECT_GT(w.statistics().chunk_count, 5u);
  }
  std::vector<std::string> topics, payloads;
  std::map<std::uint16_t, std::string> channel_topic;
  tachi::mcap::read(file, {.schema = [](const tachi::mcap::Schema& s) { EXPECT_EQ(s.name, "pkg::A"); },
                           .channel = [&](const tachi::mcap::Channel& c) { channel_topic[c.id] = c.topic; },
                           .message = [&](const tachi::mcap::Message& m) {
                             EXPECT_EQ(m.publish_time + 100, m.log_time);
                             topics.push_back(channel_topic.at(m.channel_id));
                             payloads.emplace_back(reinterpret_cast<const char*>(m.data.data()), m.data.size());
                             return true;
                           }});
  ASSERT_EQ(payloads.size(), 100u);
  for (std::size_t i = 0; i < 100; ++i) {
    EXPECT_EQ(payloads[i], "message " + std::to_string(i));
    EXPECT_EQ(topics[i], i % 3 == 0 ? "b" : "a");
  }
  const auto stats = tachi::mcap::read_statistics(file);
  EXPECT_EQ(stats.message_count, 100u);
  EXPECT_EQ(stats.channel_count, 2u);
  EXPECT_EQ(stats.schema_count, 1u);
  EXPECT_EQ(stats.channel_message_counts.at(1), 34u);  // channel b: i = 0, 3, ..., 99
  EXPECT_EQ(stats.message_start_time, 1000u);
  EXPECT_EQ(stats.message_end_time, 1099u);
}

TEST(Mcap, ADamagedChunkIsRefusedNamingTheFile) {
  tachi::test::ScratchDir dir("mcap_bad");
  const auto file = dir / "bad.mcap";
  {
    tachi::mcap::Writer w(file, "", "test");
    const auto c = w.add_channel(0, "a", "cdr");
    w.write({c, 0, 1, 1, bytes_of("a payload that will be damaged")});
  }
  std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
  std::string data((std::istreambuf_iterator<char>(f)), {});
  const auto at = data.find("damaged");
  ASSERT_NE(at, std::string::npos);
  f.seekp(static_cast<std::streamoff>(at));
  f.put('X');
  f.close();
  try {
    tachi::mcap::read(file, {});
    FAIL() << "read a damaged chunk";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("CRC"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "empty.mcap") << "not mcap";
  EXPECT_THROW(tachi::mcap::read(dir / "empty.mcap", {}), std::runtime_error);
  EXPECT_THROW(tachi::mcap::read_statistics(dir / "empty.mcap"), std::runtime_error);
}

TEST(Mcap, TheSizeLimitEstimateBoundsTheClosedFileTightly) {
  // Over many shapes of file (messages on new or known channels, chunks open or just flushed), the
  // file closed after one more message is never larger than the estimate, and at most 100 bytes smaller.
  tachi::test::ScratchDir dir("mcap_size");
  for (int messages = 1; messages <= 40; messages += 3) {
    const auto file = dir / (std::to_string(messages) + ".mcap");
    std::uint64_t estimate = 0;
    {
      tachi::mcap::Writer w(file, "", "test", 300);
      const auto s = w.add_schema("pkg::A", "omgidl", std::string(500, 'x'));
      const std::uint16_t channels[] = {w.add_channel(s, "a", "cdr", {{"qos_profile", "State"}}), w.add_channel(s, "b", "cdr"),
                                        w.add_channel(0, "c", "json")};
      for (int i = 0; i < messages; ++i) {
        const std::string payload(static_cast<std::size_t>(10 + 7 * i), 'p');
        const auto channel = channels[(i * i) % 3];
        if (i + 1 == messages) estimate = w.closed_size_with(channel, payload.size());
        w.write({channel, 0, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(i), bytes_of(payload)});
      }
    }
    const auto size = std::filesystem::file_size(file);
    EXPECT_LE(size, estimate) << messages << " messages";
    EXPECT_GE(size + 100, estimate) << messages << " messages";
  }
}
