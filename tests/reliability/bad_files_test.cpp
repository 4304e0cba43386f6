// Corrupt or odd input files: one clear error naming the file and what is wrong, or a
// counted, reported skip; never a silent drop or a misleading message.
#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/fakenect_recording.hpp"
#include "tachi/sim/stroke.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace tachi {
namespace {

using sensor::test::fakenect_depth_bytes;
using sensor::test::ramp_frame;
using sensor::test::write_text;

std::string decode_error(const std::string& bytes) {
  std::vector<std::uint16_t> raw;
  const auto r = sensor::decode_depth_pgm(bytes, raw);
  return std::holds_alternative<sensor::DepthFileError>(r) ? std::get<sensor::DepthFileError>(r).message : "ok";
}

TEST(BadFiles, APgmHeaderIsReadByTheFormatCommentsIncluded) {
  const auto raw = ramp_frame(3);
  EXPECT_EQ(decode_error(fakenect_depth_bytes(raw, "P5\n# written by a tool\n640 480\n# max\n65535\n")), "ok");
  EXPECT_EQ(decode_error(fakenect_depth_bytes(raw, "P5 640\t480   65535\n")), "ok");
}

TEST(BadFiles, TrailingGarbageAfterADepthFrameIsAnError) {
  const std::string good = fakenect_depth_bytes(ramp_frame(0));
  EXPECT_NE(decode_error(good + "xx").find("trailing garbage: 2 bytes"), std::string::npos);
  sensor::test::ScratchDir dir{"garbage"};
  const auto file = dir / "d-1.000000-1.pgm";
  write_text(file, good + std::string(50'000, 'g'));
  std::vector<std::uint16_t> raw;
  try {
    sensor::read_depth_file(file, raw);
    FAIL() << "50 KB of garbage read as a frame";
  } catch (const sensor::RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ": trailing garbage"), std::string::npos) << e.what();
  }
}

std::string index_error(const std::filesystem::path& dir) {
  try {
    (void)sensor::read_index(dir);
  } catch (const sensor::RecordingError& e) {
    return e.what();
  }
  return "no error";
}

TEST(BadFiles, AnIndexOutOfOrderAWrongSizedDumpAndADirectoryAreNamed) {
  sensor::test::ScratchDir root{"index"};
  const std::string d1 = "d-1700000000.000000-1.pgm", d2 = "d-1700000000.033333-2.pgm", a1 = "a-1700000000.010000-1.dump";
  const auto make = [&](const std::string& name, const std::string& index) {
    const auto dir = root / name;
    std::filesystem::create_directories(dir);
    for (const auto& f : {d1, d2}) write_text(dir / f, fakenect_depth_bytes(ramp_frame(0)));
    write_text(dir / a1, std::string(12, '\0'));
    write_text(dir / "INDEX.txt", index);
    return dir;
  };
  EXPECT_EQ(index_error(make("good", d1 + "\n" + a1 + "\n" + d2 + "\n")), "no error");
  EXPECT_NE(index_error(make("reversed", d2 + "\n" + d1 + "\n")).find("line 2 lists " + d1 + ": host time goes back"),
            std::string::npos);
  const auto empty_dump = make("empty_dump", d1 + "\n" + a1 + "\n");
  write_text(empty_dump / a1, "");
  EXPECT_NE(index_error(empty_dump).find(a1 + ", which is 0 bytes; an accelerometer dump is 12"), std::string::npos)
      << index_error(empty_dump);
  const auto directory = make("directory", d1 + "\n" + d2 + "\n");
  std::filesystem::remove(directory / d2);
  std::filesystem::create_directories(directory / d2);
  EXPECT_NE(index_error(directory).find(d2 + ", which is not a regular file"), std::string::npos) << index_error(directory);
  std::filesystem::remove(directory / d2);
  EXPECT_NE(index_error(directory).find(d2 + ", which does not exist"), std::string::npos);
}

TEST(BadFiles, StrokeRowsOutOfOrderOrOutOfRangeAreReportedNotSilentlyDropped) {
  std::istringstream in("t,x,y,z\n0,0,0,0\n0.1,1e30,0,0\n1e30,0,0,0\n0.2,0.1,0,0\n0.15,0.2,0,0\n0.3,0.3,0,0\n");
  const auto file = sim::parse_stroke_csv(in);
  ASSERT_TRUE(file.error.empty()) << file.error;
  // The t = 1e30 row no longer makes every later row "go back": 0.2 and 0.3 are kept.
  ASSERT_EQ(file.samples.size(), 3u);
  EXPECT_EQ(file.samples.back().t, 0.3);
  EXPECT_EQ(file.skipped_rows, 3u);
  ASSERT_EQ(file.problems.size(), 3u);
  EXPECT_NE(file.problems[0].find("line 3: position is out of range"), std::string::npos) << file.problems[0];
  EXPECT_NE(file.problems[1].find("line 4: time 1e30 s is out of range"), std::string::npos) << file.problems[1];
  EXPECT_NE(file.problems[2].find("line 6: time 0.15 s goes back"), std::string::npos) << file.problems[2];
}

TEST(BadFiles, AReversedStrokeFileSaysWhyItsRowsWereSkipped) {
  std::istringstream in("t,x,y,z\n0.3,0.3,0,0\n0.2,0.2,0,0\n0.1,0.1,0,0\n");
  const auto file = sim::parse_stroke_csv(in);
  EXPECT_EQ(file.samples.size(), 1u);
  ASSERT_EQ(file.problems.size(), 2u);
  EXPECT_NE(file.problems[0].find("goes back"), std::string::npos);
}

}  // namespace
}  // namespace tachi
