// tachi-sensor as a process: what it publishes on DDS matches what it writes to its CSV.
#include <gtest/gtest.h>


#include <chrono>
#include <cstdlib>
#include <map>

#include "paths.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "process.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

constexpr std::uint32_t kDomain = 51;

TEST(SensorProcess, PublishesOneRawHandSamplePerDepthFrameAndExitsAtTheEnd) {
  test::ScratchDir scratch("bus");
  const auto csv = scratch.path() / "hands.csv";
  const auto recording = std::filesystem::path(test::recordings_dir()) / "jitter";
  bus::Participant dds{kDomain};
  bus::Reader<tachi_msg_RawHandSample> reader{dds, bus::topics::raw_hand};

  tachi::test::ChildProcess sensor({tachi::test::executable("tachi-sensor"), "--recording", recording.string(), "--rate", "3", "--domain",
                                    std::to_string(kDomain), "--wait-readers", "1", "--sensor-id", "9", "--csv", csv.string(),
                                    "--log-level", "warn"});
  std::map<std::uint64_t, tachi_msg_RawHandSample> received;
  auto quiet_since = std::chrono::steady_clock::now();
  while (sensor.running() || std::chrono::steady_clock::now() - quiet_since < std::chrono::milliseconds(500)) {
    if (reader.wait_for_data(std::chrono::milliseconds(50))) quiet_since = std::chrono::steady_clock::now();
    for (auto& s : reader.take()) received[s->frame] = *s;
    if (std::chrono::steady_clock::now() - quiet_since > std::chrono::seconds(20)) break;
  }
  EXPECT_EQ(sensor.wait(std::chrono::seconds(30)), 0) << sensor.err();

  const auto rows = read_hand_csv(csv);
  ASSERT_EQ(rows.size(), 145u);
  EXPECT_GE(received.size(), rows.size() * 95 / 100);  // keep-last 64: a stalled reader may miss some
  EXPECT_TRUE(received.count(rows.back().frame)) << "the last sample was not flushed before exit";
  std::size_t tracked = 0;
  for (const auto& row : rows) {
    const auto it = received.find(row.frame);
    if (it == received.end()) continue;
    const auto& m = it->second;
    EXPECT_EQ(m.sensor_id, 9u);
    EXPECT_EQ(m.capture_time_ns, row.stamp_ns);
    ASSERT_EQ(m.tracked, row.tracked) << "frame " << row.frame;
    if (!row.tracked) continue;
    ++tracked;
    EXPECT_NEAR(m.position_m.x, row.position.x(), 2e-6);
    EXPECT_NEAR(m.position_m.y, row.position.y(), 2e-6);
    EXPECT_NEAR(m.position_m.z, row.position.z(), 2e-6);
    EXPECT_NEAR(m.pixel_u, row.u, 2e-3);
    EXPECT_NEAR(m.confidence, row.confidence, 1e-4);
  }
  EXPECT_GT(tracked, 100u);
}

}  // namespace
}  // namespace tachi::sensor
