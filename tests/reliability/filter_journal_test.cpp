// The filter's journal (filter/src/journal.cpp) and the sensor's playback progress: a killed filter
// restarted on its journal goes on exactly as the undisturbed one (same strokes, same ids, same
// session, the smoothed hand to the bit); a resumed sensor knows where it stopped; both files refuse
// what is not theirs, naming it. Pure: no DDS.
#include "scratch_dir.hpp"
#include "tachi/filter/journal.hpp"
#include "tachi/sensor/playback_progress.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace tachi::filter {
namespace {

// A hand reaching the cloth, sweeping across it, pulling away; lost for a few frames in the middle.
HandSample hand(int i, const FilterConfig& config) {
  const float t = static_cast<float>(i) / 30.0F;
  const float reach = i < 20 ? 0.3F - 0.015F * static_cast<float>(i) : i > 80 ? 0.015F * static_cast<float>(i - 80) : 0.0F;
  const Eigen::Vector3f world{-0.45F + 0.01F * static_cast<float>(i), 0.1F * std::sin(3.0F * t), reach};
  HandSample h;
  h.frame = static_cast<std::uint64_t>(i);
  h.stamp_ns = 1'000'000'000 + std::int64_t{i} * 33'333'333;
  h.position_m = config.workspace.to_camera(world) + Eigen::Vector3f{0.002F * std::sin(17.0F * t), 0.0F, 0.0F};
  h.tracked = i < 50 || i > 53;
  h.confidence = 0.9F;
  return h;
}

void expect_same(const StrokeSample& a, const StrokeSample& b, int i) {
  SCOPED_TRACE(i);
  EXPECT_EQ(a.position_m, b.position_m);  // bit for bit: the journal's hex floats
  EXPECT_EQ(a.gate, b.gate);
  EXPECT_EQ(a.stroke_id, b.stroke_id);
  EXPECT_EQ(a.tracked, b.tracked);
  EXPECT_EQ(a.distance_to_cloth_m, b.distance_to_cloth_m);
}

TEST(FilterJournal, AFilterKilledMidStrokeReplaysToTheSameStateAndSession) {
  tachi::test::ScratchDir dir("filter_journal");
  const FilterConfig config;
  constexpr int kSamples = 100;
  StrokeFilter undisturbed{config};
  std::vector<StrokeSample> expected;
  for (int i = 0; i < kSamples; ++i) {
    if (i == 30) (void)undisturbed.on_voice(VoiceCommandKind::Stop);  // a command mid-run: journaled too
    expected.push_back(undisturbed.on_hand(hand(i, config)));
  }
  ASSERT_GT(expected.back().stroke_id, 0u) << "the sweep opened a stroke";

  for (const int kill_at : {25, 40, 52, 70}) {
    SCOPED_TRACE(kill_at);
    const auto path = dir / ("filter" + std::to_string(kill_at) + ".journal");
    {
      FilterJournal journal(path, config, 0xabc);
      StrokeFilter filter{config};
      for (int i = 0; i < kill_at; ++i) {
        if (i == 30) {
          (void)filter.on_voice(VoiceCommandKind::Stop);
          journal.append({FilterJournalRecord::Kind::Voice, 0, {}, {}, VoiceCommandKind::Stop});
        }
        const auto out = filter.on_hand(hand(i, config));
        journal.append({FilterJournalRecord::Kind::Hand, 4, hand(i, config), {out.distance_to_cloth_m, out.hand_outside_cloth, {}}, {}});
        journal.flush();
      }
    }  // killed: the process is gone, the file stays
    FilterJournal journal(path, config, 0xdef);
    EXPECT_EQ(journal.session_id(), 0xabcu) << "a restart carries the first run's session on";
    StrokeFilter restarted{config};
    const FilterReplay replayed = replay(journal.recovered(), restarted);
    ASSERT_TRUE(replayed.last.has_value());
    expect_same(replayed.last->second, expected[static_cast<std::size_t>(kill_at - 1)], kill_at - 1);
    // The sensor's history re-delivers the last samples: the journaled ones are recognised.
    EXPECT_TRUE(replayed.processed.contains(4, hand(kill_at - 1, config).stamp_ns));
    EXPECT_FALSE(replayed.processed.contains(4, hand(kill_at, config).stamp_ns));
    EXPECT_FALSE(replayed.processed.contains(5, hand(kill_at - 1, config).stamp_ns)) << "another sensor's sample is new";
    for (int i = kill_at; i < kSamples; ++i) {
      if (i == 30) (void)restarted.on_voice(VoiceCommandKind::Stop);
      expect_same(restarted.on_hand(hand(i, config)), expected[static_cast<std::size_t>(i)], i);
    }
  }
}

TEST(FilterJournal, ATornLastLineIsDroppedAnotherConfigAndCorruptLinesAreRefusedNamingTheFile) {
  tachi::test::ScratchDir dir("filter_journal_bad");
  const FilterConfig config;
  const auto path = dir / "f.journal";
  {
    FilterJournal journal(path, config, 7);
    journal.append({FilterJournalRecord::Kind::Hand, 1, hand(3, config), {0.5F, false, {}}, {}});
    journal.flush();
  }
  { std::ofstream(path, std::ios::app) << "h 1 4 1133"; }  // a kill mid-write
  {
    FilterJournal journal(path, config, 8);
    EXPECT_EQ(journal.recovered().size(), 1u);
    EXPECT_EQ(journal.session_id(), 7u);
    EXPECT_EQ(journal.recovered()[0].hand.position_m, hand(3, config).position_m);
  }
  FilterConfig other = config;
  other.gate.enter_distance_m = 0.04F;
  try {
    FilterJournal journal(path, other, 9);
    FAIL() << "a journal of another configuration was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("another configuration"), std::string::npos) << e.what();
  }
  { std::ofstream(path, std::ios::app) << "x garbage\nv 1\n"; }
  try {
    FilterJournal journal(path, config, 9);
    FAIL() << "a corrupt line in the middle was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 4 is corrupt"), std::string::npos) << e.what();
  }
}

TEST(FilterJournal, ProcessedSamplesStayBounded) {
  ProcessedSamples seen;
  for (std::int64_t t = 0; t < 1000; ++t) seen.add(1, t);
  EXPECT_TRUE(seen.contains(1, 999));
  EXPECT_FALSE(seen.contains(1, 100)) << "only the newest 256 per sensor are kept";
  for (std::uint32_t sensor = 2; sensor < 200; ++sensor) seen.add(sensor, 1);
  EXPECT_TRUE(seen.contains(60, 1));
  EXPECT_FALSE(seen.contains(150, 1)) << "at most 64 sensors are tracked";
}

}  // namespace
}  // namespace tachi::filter

namespace tachi::sensor {
namespace {

TEST(PlaybackProgress, ARestartedSensorKnowsWhereTheKilledOneStopped) {
  tachi::test::ScratchDir dir("playback_progress");
  const auto path = dir / "sensor.progress";
  {
    PlaybackProgress progress(path);
    EXPECT_EQ(progress.resumed_after(), 0u) << "a new file: play from the top";
    for (std::uint64_t frame = 1; frame <= 57; ++frame) progress.record(frame);
  }
  EXPECT_EQ(PlaybackProgress(path).resumed_after(), 57u);
  { std::ofstream(path, std::ios::trunc) << "57 frames\n"; }
  try {
    PlaybackProgress progress(path);
    FAIL() << "a corrupt progress file was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(PlaybackProgress{dir.path()}, std::runtime_error) << "a directory";
}

}  // namespace
}  // namespace tachi::sensor
