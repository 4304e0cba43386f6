#include "tachi/sensor/fakenect_recording.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "tachi/sensor/depth_source.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

using test::ScratchDir;
using test::write_text;

TEST(FakenectIndex, ParsesFakenectRecordNames) {
  const auto e = parse_index_line("d-1290000000.123456-4294967295.pgm");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, EntryKind::Depth);
  EXPECT_EQ(e->host_time_ns, 1290000000123456000LL);
  EXPECT_EQ(e->device_timestamp, 4294967295u);
  EXPECT_EQ(e->file, "d-1290000000.123456-4294967295.pgm");
  EXPECT_EQ(parse_index_line("a-1.5-7.dump")->kind, EntryKind::Accel);
  EXPECT_EQ(parse_index_line("r-1.000001-0.ppm\r")->host_time_ns, 1'000'001'000LL);
}

TEST(FakenectIndex, RejectsGarbageLinesWithAReason) {
  std::string why;
  for (const char* bad : {"hello world", "d-abc-12.pgm", "d-1.0-12.ppm", "x-1.0-1.pgm", "d-1.0-.pgm", "d-1.0-12",
                          "d-1.0-99999999999.pgm", "d-../1.0-1.pgm", ""}) {
    EXPECT_FALSE(parse_index_line(bad, &why)) << bad;
    EXPECT_FALSE(why.empty()) << bad;
  }
}

TEST(FakenectDepthFile, DecodesLittleEndianDisparity) {
  const auto raw = test::ramp_frame(5);
  const std::string bytes = test::fakenect_depth_bytes(raw);
  std::vector<std::uint16_t> out;
  const auto r = decode_depth_pgm(bytes, out);
  ASSERT_TRUE(std::holds_alternative<std::monostate>(r));
  EXPECT_EQ(out, raw);
}

TEST(FakenectDepthFile, ReportsTruncatedBadHeaderAndBigEndianFiles) {
  std::vector<std::uint16_t> out;
  const auto message = [&](const std::string& bytes) {
    const auto r = decode_depth_pgm(bytes, out);
    return std::holds_alternative<DepthFileError>(r) ? std::get<DepthFileError>(r).message : std::string("ok");
  };
  const std::string good = test::fakenect_depth_bytes(test::ramp_frame(0));
  EXPECT_NE(message(good.substr(0, 1017)).find("truncated: 1000 of 614400"), std::string::npos);
  EXPECT_NE(message("P6 640 480 255\n" + good.substr(17)).find("bad header"), std::string::npos);
  EXPECT_NE(message(test::fakenect_depth_bytes(std::vector<std::uint16_t>(320 * 240, 1), "P5 320 240 65535\n")).find("320x240"),
            std::string::npos);
  EXPECT_NE(message("P5 640 480\n").find("bad header"), std::string::npos);
  EXPECT_NE(message("").find("bad header"), std::string::npos);
  // A real (big-endian) PGM of the same frame: every byte pair swapped.
  std::vector<std::uint16_t> swapped = test::ramp_frame(0);
  for (auto& v : swapped) v = static_cast<std::uint16_t>((v >> 8) | (v << 8));
  EXPECT_NE(message(test::fakenect_depth_bytes(swapped)).find("big-endian"), std::string::npos);
}

/// A small valid recording: `frames` depth frames 1/30 s apart, each followed by an accelerometer entry.
void write_recording(const std::filesystem::path& dir, int frames, std::int64_t gap_ns = 33'333'000LL) {
  FakenectWriter writer(dir);
  for (int i = 0; i < frames; ++i) {
    DepthFrame f;
    f.stamp_ns = 1'700'000'000'000'000'000LL + i * gap_ns;
    f.device_timestamp = static_cast<std::uint32_t>(1000 + i);
    f.raw = test::ramp_frame(static_cast<std::uint16_t>(i));
    writer.write_depth(f);
    writer.write_accel(f.stamp_ns + 1'000'000, f.device_timestamp, AccelSample{});
  }
}

TEST(RecordingSource, PlaysBackWhatTheWriterWrote) {
  ScratchDir dir("roundtrip");
  write_recording(dir.path(), 3);
  RecordingSource source(dir.path(), Playback{0.0, false});
  ASSERT_EQ(source.depth_frame_count(), 3u);
  for (int i = 0; i < 3; ++i) {
    const auto f = source.next();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame, static_cast<std::uint64_t>(i));
    EXPECT_EQ(f->stamp_ns, 1'700'000'000'000'000'000LL + i * 33'333'000LL);
    EXPECT_EQ(f->device_timestamp, static_cast<std::uint32_t>(1000 + i));
    EXPECT_EQ(f->raw, test::ramp_frame(static_cast<std::uint16_t>(i)));
  }
  EXPECT_FALSE(source.next());
  const auto entries = read_index(dir.path());
  ASSERT_EQ(entries.size(), 6u);
  EXPECT_EQ(entries[1].kind, EntryKind::Accel);
  EXPECT_EQ(std::filesystem::file_size(dir.path() / entries[1].file), 12u);
  EXPECT_EQ(std::filesystem::file_size(dir.path() / entries[0].file), 17u + 614400u);
}

TEST(RecordingSource, WriterRefusesAFolderThatHoldsARecording) {
  ScratchDir dir("refuse");
  write_recording(dir.path(), 1);
  EXPECT_THROW(FakenectWriter{dir.path()}, RecordingError);
}

TEST(RecordingSource, PacesByRecordedHostTimeAndRate) {
  ScratchDir dir("pace");
  write_recording(dir.path(), 7);  // six gaps of 33.333 ms: 200 ms of recording
  const auto play = [&](double rate) {
    RecordingSource source(dir.path(), Playback{rate, false});
    const auto start = std::chrono::steady_clock::now();
    while (source.next()) {
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  const double real = play(1.0), doubled = play(2.0);
  // Never early; late only by the machine's load (the tests share two cores), so the upper
  // bounds compare the runs with each other rather than with the clock.
  EXPECT_GE(real, 199.0);
  EXPECT_LT(real, 1500.0);
  EXPECT_GE(doubled, 99.0);
  EXPECT_LT(doubled, real);
  // As fast as it can: no waiting on a recording of six 1 s gaps. Seven 614 KB reads from the page cache
  // take ~10 ms, and 130 ms sanitized on a loaded machine (where comparing them with the doubled pace's
  // 100 ms of waiting failed), against the 6 s a paced playback would wait.
  ScratchDir slow("pace_slow");
  write_recording(slow.path(), 7, 1'000'000'000LL);
  RecordingSource source(slow.path(), Playback{0.0, false});
  const auto start = std::chrono::steady_clock::now();
  int frames = 0;
  while (source.next()) ++frames;
  const double max = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(frames, 7);
  EXPECT_LT(max, 3000.0);
}

TEST(RecordingSource, LoopsWithAMonotonicTimeline) {
  ScratchDir dir("loop");
  write_recording(dir.path(), 2);
  RecordingSource source(dir.path(), Playback{0.0, true});
  std::int64_t previous = 0;
  for (int i = 0; i < 7; ++i) {
    const auto f = source.next();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame, static_cast<std::uint64_t>(i));
    EXPECT_GT(f->stamp_ns, previous);
    EXPECT_EQ(f->raw, test::ramp_frame(static_cast<std::uint16_t>(i % 2)));
    previous = f->stamp_ns;
  }
}

std::string error_of(const std::filesystem::path& dir, bool read_all) {
  try {
    RecordingSource source(dir, Playback{0.0, false});
    while (read_all && source.next()) {
    }
  } catch (const RecordingError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RecordingSource, CorruptRecordingsGiveClearErrors) {
  ScratchDir root("corrupt");
  const std::string good_name = "d-1700000000.000000-1.pgm";
  const std::string good = test::fakenect_depth_bytes(test::ramp_frame(0));
  const auto make = [&](const std::string& name, const std::string& index) {
    const auto dir = root.path() / name;
    std::filesystem::create_directories(dir);
    write_text(dir / good_name, good);
    write_text(dir / "INDEX.txt", index);
    return dir;
  };
  EXPECT_NE(error_of(root.path() / "nothing_here", false).find("cannot open INDEX.txt"), std::string::npos);
  std::filesystem::create_directories(root.path() / "no_index");
  EXPECT_NE(error_of(root.path() / "no_index", false).find("cannot open INDEX.txt"), std::string::npos);
  EXPECT_NE(error_of(make("garbage", good_name + "\nthis is not a frame\n"), false).find("INDEX.txt line 2 \"this is not a frame\""),
            std::string::npos);
  EXPECT_NE(error_of(make("binary", std::string("\x01\x02\xff\n", 4)), false).find("INDEX.txt line 1"), std::string::npos);
  EXPECT_NE(error_of(make("missing", good_name + "\nd-1700000000.033333-2.pgm\n"), false).find("which does not exist"),
            std::string::npos);
  EXPECT_NE(error_of(make("no_depth", "\n"), false).find("no depth frames"), std::string::npos);

  const auto truncated = make("truncated", good_name + "\n");
  write_text(truncated / good_name, good.substr(0, 5000));
  EXPECT_NE(error_of(truncated, true).find("truncated"), std::string::npos);
  const auto bad_header = make("bad_header", good_name + "\n");
  write_text(bad_header / good_name, "P2 640 480 65535\n" + good.substr(17));
  EXPECT_NE(error_of(bad_header, true).find("bad header"), std::string::npos);
  // The good one reads (so the failures above are the corruption, not the harness).
  EXPECT_EQ(error_of(make("good", good_name + "\n"), true), "no error");
}

}  // namespace
}  // namespace tachi::sensor
