// `tachi hz|bw|topics --verbose|echo --field` on real publishers (domains 143-144; tests/launcher
// owns 120-149, docs/testing.md).
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>
#include <regex>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

namespace {
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

// The figures of the last report of `tachi hz` / `tachi bw`.
double last_number_after(const std::string& text, const std::string& label) {
  const auto at = text.rfind(label);
  return at == std::string::npos ? -1 : std::stod(text.substr(at + label.size()));
}
}  // namespace

TEST(TachiHzAndBw, ASensorPlayingA30HzRecordingIs30Hz) {
  // The recording's depth frames are 1/30 s apart; the sensor publishes one raw hand sample per frame.
  ChildProcess sensor({kBin + "/tachi-sensor", "--recording", kRecordings + "/straight_cut", "--loop", "--domain", "143"});
  // hz and bw listen side by side, as two terminals would; then topics, with the sensor surely discovered.
  ChildProcess bw_run({kBin + "/tachi", "bw", "tachi/hand/raw", "--domain", "143", "--duration", "3"});
  const auto hz = tachi::test::run({kBin + "/tachi", "hz", "tachi/hand/raw", "--domain", "143", "--duration", "6"}, 60s);
  const int bw_exit = bw_run.wait(60s);
  const tachi::test::RunResult bw{bw_exit, bw_run.out(), bw_run.err()};
  const auto topics = tachi::test::run({kBin + "/tachi", "topics", "--verbose", "--domain", "143"}, 60s);
  sensor.signal(SIGINT);
  EXPECT_EQ(sensor.wait(10s), 0) << sensor.err();

  ASSERT_EQ(hz.exit_code, 0) << hz.err;
  EXPECT_NEAR(last_number_after(hz.out, "average rate: "), 30.0, 1.0) << hz.out;
  EXPECT_NE(hz.out.find("std dev: "), std::string::npos) << hz.out;
  EXPECT_GE(last_number_after(hz.out, "window: "), 100) << "~5 s of samples: " << hz.out;

  ASSERT_EQ(bw.exit_code, 0) << bw.err;
  // Bandwidth = rate x message size: a raw hand sample is ~60 B of CDR, so ~1.8 KB/s.
  // Its last report, as for hz: the first covers the first second only, and once measured 34.7 Hz (31
  // messages, one of them early in the window) where the third, over 90 messages, read 31.4 Hz.
  const std::regex report(R"(([0-9.]+) (B|KB)/s from ([0-9]+) messages\n\tMessage size mean: ([0-9.]+) (B|KB))");
  std::smatch m;
  for (auto it = std::sregex_iterator(bw.out.begin(), bw.out.end(), report); it != std::sregex_iterator(); ++it) m = *it;
  ASSERT_FALSE(m.empty()) << bw.out;
  const auto bytes = [](const std::string& v, const std::string& unit) { return std::stod(v) * (unit == "KB" ? 1000 : 1); };
  const double rate_bytes = bytes(m[1], m[2]), size_bytes = bytes(m[4], m[5]);
  EXPECT_GT(size_bytes, 40);
  EXPECT_LT(size_bytes, 100);
  EXPECT_NEAR(rate_bytes / size_bytes, 30.0, 2.0) << bw.out;

  ASSERT_EQ(topics.exit_code, 0) << topics.err;
  // The sensor's writer offers SensorData: reliable, transient-local, keep the last 64 per key.
  EXPECT_NE(topics.out.find("writer tachi-sensor"), std::string::npos) << topics.out;
  EXPECT_NE(topics.out.find("QoS: reliable, transient-local, keep-last 64"), std::string::npos) << topics.out;
  EXPECT_NE(topics.out.find("liveliness automatic 3 s"), std::string::npos) << "the heartbeat's lease: " << topics.out;
}

TEST(TachiEcho, EveryTopicTheRegistryListsIncludingTheSceneObjectAndOneField) {
  tachi::test::ScratchDir dir("tachi_echo_object");
  std::ofstream(dir / "tri.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                    "end_header\n0 0 0.1\n0.1 0 0.1\n0 0.1 0.1\n";
  ChildProcess sim({kBin + "/tachi-sim", "--grid", "8", "--object", (dir / "tri.ply").string(), "--domain", "144"});
  const auto points = tachi::test::run({kBin + "/tachi", "echo", "tachi/scene/object", "--domain", "144", "--count", "1",
                                        "--field", "points", "--timeout", "30"},
                                       60s);
  const auto bad_field = tachi::test::run({kBin + "/tachi", "echo", "tachi/scene/object", "--domain", "144", "--count", "1",
                                           "--field", "pionts", "--timeout", "30"},
                                          60s);
  sim.signal(SIGINT);
  EXPECT_EQ(sim.wait(10s), 0) << sim.err();
  ASSERT_EQ(points.exit_code, 0) << points.err;
  const auto p = nlohmann::json::parse(points.out, nullptr, false);
  ASSERT_TRUE(p.is_array()) << points.out;
  EXPECT_EQ(p.size(), 9u) << "x, y, z of the three points: " << points.out;
  EXPECT_EQ(bad_field.exit_code, 2);
  EXPECT_NE(bad_field.err.find("--field pionts: no such field in tachi/scene/object (its fields: cloth_id, points, session_id)"),
            std::string::npos)
      << bad_field.err;
  const auto unknown = tachi::test::run({kBin + "/tachi", "echo", "tachi/scene/objet", "--domain", "144"}, 30s);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("tachi/scene/object"), std::string::npos) << "the known topics, from the registry: " << unknown.err;
}
