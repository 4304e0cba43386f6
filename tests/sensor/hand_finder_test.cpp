#include "tachi/sensor/hand_finder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "tachi/sensor/synthetic.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

struct ScenarioRun {
  std::vector<HandRow> hands;
  std::vector<TruthRow> truth;
  std::vector<std::uint16_t> nearest_raw;  // nearest valid reading of each frame
};

ScenarioRun run_scenario(const std::string& name) {
  const auto dir = std::filesystem::path(test::recordings_dir()) / name;
  ScenarioRun run;
  run.truth = read_truth_csv(dir / "ground_truth.csv");
  RecordingSource source(dir, Playback{0.0, false});
  HandFinder finder(source.model());
  while (auto frame = source.next()) {
    const auto hand = finder.find(*frame);
    HandRow row;
    row.frame = frame->frame;
    row.tracked = hand.tracked;
    row.position = hand.position_m.cast<double>();
    run.hands.push_back(row);
    run.nearest_raw.push_back(*std::min_element(frame->raw.begin(), frame->raw.end()));
  }
  return run;
}

/// The accuracy targets, for every bundled scenario: RMS <= 1 cm, >= 99% of the visible frames
/// tracked, no phantom frame.
class ScenarioAccuracy : public ::testing::TestWithParam<std::string> {};

TEST_P(ScenarioAccuracy, MeetsTheTargets) {
  const auto run = run_scenario(GetParam());
  const Evaluation e = evaluate(run.hands, run.truth);
  EXPECT_EQ(e.missing_frames, 0u);
  EXPECT_GE(e.visible, 50u);  // enough visible frames for the ratio to mean something
  EXPECT_LE(e.rms_m, 0.010);
  EXPECT_GE(e.tracked_ratio, 0.99);
  EXPECT_EQ(e.phantoms, 0u);
  // No frame far off: a palm cut by the image border is not reported 4-5 cm inward of its centre,
  // nor an edge-on palm placed on its fingers.
  EXPECT_LE(e.max_m, 0.02);
  RecordProperty("rms_mm", std::to_string(e.rms_m * 1000));
}

INSTANTIATE_TEST_SUITE_P(Bundled, ScenarioAccuracy, ::testing::ValuesIn(test::scenario_names()));

TEST(HandFinder, APalmTurnedUpTo60DegreesFromTheLineOfSightIsTrackedWithin1Cm) {
  // turned_palm: yaw 60 degrees about y, so along its path the palm is seen 49-77 degrees from the
  // line of sight. Up to 60 degrees, every visible frame is tracked and within 1 cm.
  const auto run = run_scenario("turned_palm");
  const Eigen::Vector3d normal(-std::sin(60.0 * std::numbers::pi / 180), 0.0, -std::cos(60.0 * std::numbers::pi / 180));  // toward the sensor
  int checked = 0;
  for (std::size_t i = 0; i < run.truth.size(); ++i) {
    const auto& truth = run.truth[i];
    if (!truth.visible || -normal.dot(truth.position.normalized()) < std::cos(60.0 * std::numbers::pi / 180)) continue;
    ++checked;
    ASSERT_TRUE(run.hands[i].tracked) << "frame " << truth.frame;
    EXPECT_LE((run.hands[i].position - truth.position).norm(), 0.01) << "frame " << truth.frame;
  }
  EXPECT_GE(checked, 20);
}

TEST(HandFinder, APalmSeenNearlyEdgeOnIsPlacedWithin15MmWithLowerConfidence) {
  // turned_palm beyond 63 degrees from the line of sight (33 visible frames, up to 77 degrees):
  // the flattest place may be among the fingers there, so the centre is placed by the hand's shape.
  // Every such frame is tracked, within 1.5 cm (12.9 mm measured), 1 cm RMS, at half confidence.
  const auto dir = std::filesystem::path(test::recordings_dir()) / "turned_palm";
  const auto truth = read_truth_csv(dir / "ground_truth.csv");
  RecordingSource source(dir, Playback{0.0, false});
  HandFinder finder(source.model());
  const Eigen::Vector3d normal(-std::sin(60.0 * std::numbers::pi / 180), 0.0, -std::cos(60.0 * std::numbers::pi / 180));  // toward the sensor
  int checked = 0;
  double sum_squares = 0;
  for (std::size_t i = 0; auto frame = source.next(); ++i) {
    const auto hand = finder.find(*frame);
    ASSERT_LT(i, truth.size());
    if (!truth[i].visible || -normal.dot(truth[i].position.normalized()) >= std::cos(63.0 * std::numbers::pi / 180)) continue;
    ++checked;
    ASSERT_TRUE(hand.tracked) << "frame " << truth[i].frame;
    const double error = (hand.position_m.cast<double>() - truth[i].position).norm();
    EXPECT_LE(error, 0.015) << "frame " << truth[i].frame;
    // Placed, not measured: half confidence (near 63 degrees the finder's own plane may still
    // measure the palm, within a degree or two).
    if (-normal.dot(truth[i].position.normalized()) < std::cos(65.0 * std::numbers::pi / 180)) {
      EXPECT_LE(hand.confidence, 0.5f) << "frame " << truth[i].frame;
    }
    sum_squares += error * error;
  }
  EXPECT_GE(checked, 30);
  EXPECT_LE(std::sqrt(sum_squares / std::max(1, checked)), 0.010);
}

TEST(HandFinder, AHandRisingThroughWhereTheArmRestedIsFoundInItsFirstVisibleFrame) {
  // second_person: the hand rises from below the image, through where the arm hung; there it is
  // less than foreground_m in front of the learnt background, so the foreground holds only its
  // fingers. The palm is measured in a ROI grown beyond them.
  const auto run = run_scenario("second_person");
  const auto first = std::find_if(run.truth.begin(), run.truth.end(), [](const TruthRow& t) { return t.visible; });
  ASSERT_NE(first, run.truth.end());
  const auto i = static_cast<std::size_t>(first - run.truth.begin());
  ASSERT_TRUE(run.hands[i].tracked) << "frame " << first->frame;
  EXPECT_LE((run.hands[i].position - first->position).norm(), 0.01);
}

TEST(HandFinder, AHandHeldStillFromTheFirstFrameIsFoundInThatFrame) {
  // Without a background that lacks the hand and without motion: found as an arm's end.
  const auto run = run_scenario("still_start");
  ASSERT_TRUE(run.truth.front().visible);
  ASSERT_TRUE(run.hands.front().tracked);
  EXPECT_LT((run.hands.front().position - run.truth.front().position).norm(), 0.01);
}

TEST(HandFinder, StaticObjectNearerThanTheHandDoesNotStealTheTrack) {
  const auto run = run_scenario("straight_cut");
  const DepthModel model;
  int checked = 0, missed = 0;
  for (std::size_t i = 0; i < run.truth.size(); ++i) {
    if (!run.truth[i].visible) continue;
    // The box in the corner is nearer than the hand in every frame: a nearest-blob rule fails.
    ASSERT_LT(model.metres(run.nearest_raw[i]) + 0.1, run.truth[i].position.z()) << "frame " << i;
    if (!run.hands[i].tracked) {
      ++missed;  // the palm circle at the image edge, as the hand leaves
      continue;
    }
    EXPECT_LT((run.hands[i].position - run.truth[i].position).norm(), 0.02) << "frame " << i;
    ++checked;
  }
  EXPECT_GT(checked, 95);
  EXPECT_LE(missed, 1);
}

TEST(HandFinder, PausingHandStaysTracked) {
  const auto run = run_scenario("straight_cut");
  // The scenario holds the hand nearly still for 1 s at the end of the cut (t 3.0-4.0 s).
  int still = 0;
  for (std::size_t i = 92; i < 118; ++i) {
    ASSERT_TRUE(run.truth[i].visible);
    EXPECT_LT((run.truth[i].position - run.truth[i - 1].position).norm(), 0.003);
    EXPECT_TRUE(run.hands[i].tracked) << "frame " << i;
    ++still;
  }
  EXPECT_EQ(still, 26);
}

TEST(HandFinder, ObjectPutDownNearerThanTheHandMidTakeDoesNotStealTheTrack) {
  ScenarioSpec spec;
  spec.name = "box_appears";
  spec.seed = 12;
  spec.distractor_from_s = 1.0;  // the box appears while the hand is up, nearer than it
  spec.path = {{0.0, Eigen::Vector3d::Zero(), true},
               {0.5, Eigen::Vector3d(-0.25, 0.0, 0.98), false},
               {2.0, Eigen::Vector3d(0.15, -0.05, 0.98), false}};
  SyntheticScene scene(spec);
  HandFinder finder{DepthModel{}};
  GroundTruth truth;
  int tracked_after = 0;
  for (std::uint64_t i = 0; i < scene.frame_count(); ++i) {
    const auto frame = scene.render(i, truth);
    const auto hand = finder.find(frame);
    if (static_cast<double>(i) / spec.fps < 1.0 || !truth.visible) continue;
    ASSERT_TRUE(hand.tracked) << "frame " << i;
    EXPECT_LT((hand.position_m.cast<double>() - truth.palm).norm(), 0.02) << "frame " << i;
    ++tracked_after;
  }
  EXPECT_GT(tracked_after, 25);
  // And a finder that only starts once the box is there does not take the box for a hand either.
  HandFinder late{DepthModel{}};
  SyntheticScene again(spec);
  const DepthModel model;
  int late_tracked = 0;
  for (std::uint64_t i = 0; i < again.frame_count(); ++i) {
    const auto frame = again.render(i, truth);
    const float nearest = model.metres(*std::min_element(frame.raw.begin(), frame.raw.end()));
    if (static_cast<double>(i) / spec.fps < 1.0) {
      EXPECT_GT(nearest, 0.85f) << "frame " << i << ": the box is there too early";
      continue;
    }
    EXPECT_LT(nearest, 0.81f) << "frame " << i << ": the box (nearer than the hand) is missing";
    const auto hand = late.find(frame);
    if (hand.tracked) {
      EXPECT_LT((hand.position_m.cast<double>() - truth.palm).norm(), 0.02) << "frame " << i;
      ++late_tracked;
    }
  }
  EXPECT_GT(late_tracked, 10);  // once the hand has moved off its first place
}

TEST(HandFinder, NoPhantomWhenNoHandIsRaised) {
  ScenarioSpec spec;
  spec.name = "idle";
  spec.seed = 11;
  spec.path = {{0.0, Eigen::Vector3d::Zero(), true}, {1.5, Eigen::Vector3d::Zero(), true}};
  SyntheticScene scene(spec);
  HandFinder finder{DepthModel{}};
  GroundTruth truth;
  for (std::uint64_t i = 0; i < scene.frame_count(); ++i) {
    const auto hand = finder.find(scene.render(i, truth));
    EXPECT_FALSE(hand.tracked) << "frame " << i;
    EXPECT_EQ(hand.confidence, 0.0f);
  }
}

TEST(HandFinder, ReportsPalmCentreInMetresWithConfidence) {
  const auto dir = std::filesystem::path(test::recordings_dir()) / "jitter";
  RecordingSource source(dir, Playback{0.0, false});
  const auto truth = read_truth_csv(dir / "ground_truth.csv");
  HandFinder finder(source.model());
  HandObservation last;
  std::size_t i = 0;
  for (; i < 60; ++i) last = finder.find(*source.next());
  ASSERT_TRUE(last.tracked);
  EXPECT_GT(last.confidence, 0.5f);
  EXPECT_LE(last.confidence, 1.0f);
  EXPECT_NEAR(last.palm_radius_m, 0.041, 0.008);
  EXPECT_LT((last.position_m.cast<double>() - truth[i - 1].position).norm(), 0.01);
  const Eigen::Vector3d back = source.model().back_project(last.u, last.v, last.position_m.z());
  EXPECT_LT((back.cast<float>() - last.position_m).norm(), 1e-5f);
}

TEST(HandFinder, WrongSizedFrameIsUntrackedNotACrash) {
  HandFinder finder{DepthModel{}};
  std::vector<std::uint16_t> small(100, 800);
  EXPECT_FALSE(finder.find(small).tracked);
  std::vector<std::uint16_t> empty;
  EXPECT_FALSE(finder.find(empty).tracked);
  std::vector<std::uint16_t> blank(kDepthPixels, kNoReading);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(finder.find(blank).tracked);
}

}  // namespace
}  // namespace tachi::sensor
