#include "tachi/sensor/random_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>

#include "tachi/sensor/clip_score.hpp"

namespace tachi::sensor {
namespace {

TEST(RandomScene, SameSeedSameSceneOtherSeedOtherScene) {
  const auto a = random_scenario(17), b = random_scenario(17), c = random_scenario(18);
  ASSERT_EQ(a.path.size(), b.path.size());
  for (std::size_t i = 0; i < a.path.size(); ++i) {
    EXPECT_EQ(a.path[i].t, b.path[i].t);
    EXPECT_EQ(a.path[i].p, b.path[i].p);
  }
  EXPECT_EQ(a.user_offset, b.user_offset);
  EXPECT_EQ(a.objects.size(), b.objects.size());
  EXPECT_NE(a.user_offset, c.user_offset);
}

// The distributions cover every kind of scene docs/sensor.md's "Randomized world" lists (over the tuning
// range's first 300 seeds: only the specs are drawn, nothing is rendered).
TEST(RandomScene, DrawsEveryKindOfSceneTheIssueNames) {
  int starts[3] = {0, 0, 0}, left = 0, near_objects = 0, moved_in = 0, walking = 0, standing = 0, turned = 0, tremor = 0;
  double nearest_user = 10, farthest_user = 0;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    const auto s = random_scenario(seed);
    ++starts[static_cast<int>(random_start(s))];
    left += s.left_handed;
    const double torso_z = 1.47 + s.user_offset.z();
    nearest_user = std::min(nearest_user, torso_z);
    farthest_user = std::max(farthest_user, torso_z);
    double hand_min_z = 10;
    for (const auto& k : s.path) {
      ASSERT_TRUE(k.rest || (k.p.z() >= 0.5 && k.p.z() <= 2.5)) << "seed " << seed;
      if (!k.rest) hand_min_z = std::min(hand_min_z, k.p.z());
    }
    for (std::size_t i = 1; i < s.path.size(); ++i) ASSERT_GT(s.path[i].t, s.path[i - 1].t) << "seed " << seed;
    for (const auto& o : s.objects) {
      near_objects += o.max.z() < hand_min_z;
      moved_in += o.slide_s > 0;
    }
    walking += s.second_person && !s.second_person_standing;
    standing += s.second_person && s.second_person_standing;
    turned += std::abs(s.palm_yaw_deg) > 30;
    tremor += s.jitter_m > 0;
  }
  EXPECT_GT(starts[0], 60);  // up from the first frame
  EXPECT_GT(starts[1], 60);  // raised later
  EXPECT_GT(starts[2], 10);  // never raised
  EXPECT_GT(left, 10);
  EXPECT_LT(nearest_user, 0.9);
  EXPECT_GT(farthest_user, 2.4);
  EXPECT_GT(near_objects, 50);
  EXPECT_GT(moved_in, 30);
  EXPECT_GT(walking, 20);
  EXPECT_GT(standing, 10);
  EXPECT_GT(turned, 20);
  EXPECT_GT(tremor, 100);
}

TEST(RandomScene, ANeverRaisedHandIsNeverRaisedNorVisible) {
  std::uint64_t seed = 1;
  while (random_start(random_scenario(seed)) != HandStart::kNeverRaised) ++seed;
  SyntheticScene scene(random_scenario(seed));
  for (std::uint64_t i = 0; i < scene.frame_count(); i += 10) {
    GroundTruth t;
    scene.render(i, t);
    EXPECT_FALSE(t.raised);
    EXPECT_FALSE(t.visible);
  }
}

HandObservation at(const Eigen::Vector3d& p) {
  HandObservation h;
  h.tracked = true;
  h.position_m = p.cast<float>();
  return h;
}

// Tuning seed 86: the hand is up from the first frame, fingers together, with the upper arm
// level at the hand's depth; its end (4.5 cm in radius, a palm-sized circle) took the track from
// frame 0 for 45 frames. A palm's widest place is short, a tube's runs along it
// (max_palm_ridge_m): no tracked point may be on the arm now. With max_palm_ridge_m raised to
// 1 m (no ridge test) and without the dome test (which now refuses the round end as well) the
// elbow is taken again, so this can fail.
TEST(RandomScene, AnElbowAtTheHandsDepthDoesNotStartATrack) {
  const auto captured_early = [](const HandFinderParams& params) {
    int captured = 0;
    score_clip(random_scenario(86), params, [&](const GroundTruth& truth, const HandObservation& hand) {
      if (truth.frame < 45 && hand.tracked && (hand.position_m.cast<double>() - truth.palm).norm() > kCaptureDistanceM) ++captured;
    });
    return captured;
  };
  EXPECT_EQ(captured_early({}), 0);
  HandFinderParams no_ridge_test;
  no_ridge_test.max_palm_ridge_m = 1.0;
  no_ridge_test.max_foreground_new_palm_ridge_m = 1.0;
  no_ridge_test.dome_significance = 0;
  // Since session 47 the elbow's circle, 25 cm below the fingertips, is also too far from the candidate's
  // nearest reading (max_new_palm_from_nearest_m): off here too.
  no_ridge_test.max_new_palm_from_nearest_m = 0;
  EXPECT_GT(captured_early(no_ridge_test), 3);
}

// The hand leaves the image across a side with the arm bent; the bend, its nearest reading at the
// border, holds a palm-sized circle. Tuning seed 46 (session 35, the hanging world; seed 42 on the
// floating world, 31 frames): a user 2 m away holds the hand out of the image's side for 26 frames,
// the bend 34 cm from the palm. A track does not start where a component's nearest reading is at the
// border (nearest_border_cells), nor where its front surface runs out of the image beyond a hand's
// reach (front_in_view_beyond_hand): either refuses the bend; with both off it is taken for those 26
// frames, so this can fail.
TEST(RandomScene, AnArmLeavingTheImageDoesNotStartATrackAtItsBend) {
  const auto captured = [](const HandFinderParams& params) {
    return score_clip(random_scenario(46), params).captured;
  };
  EXPECT_EQ(captured({}), 0u);
  HandFinderParams no_nearest_test;
  no_nearest_test.nearest_border_cells = -1;
  EXPECT_EQ(captured(no_nearest_test), 0u);
  HandFinderParams no_border_test = no_nearest_test;
  no_border_test.front_in_view_beyond_hand = false;
  EXPECT_GT(captured(no_border_test), 20u);
}

// The elbow nearer the camera than the hand (a hand raised high beside the head, the elbow
// pointing at the camera, 5-9 cm nearer). The arm's hand is its geodesic end (arm_end), not its
// nearest reading. Tuning seed 25: the hand is up and still from the first frame (acquired without
// a background, find_arm_end): the elbow was taken from frame 0 for 51 frames, 34 cm off. Tuning
// seed 292 (session 35, the hanging world; seed 3 on the floating world, whose rise from the hanging
// arm now costs a frame 20 cm off): a user 1.2 m away, the hand up from the first frame, the elbow
// 6 cm nearer; it was taken for 21 frames running, 31 cm below the hand. With
// arm_end_window_m negative (no geodesic end), without the dome test (which now refuses these
// elbows as well) and with a followed palm sought anywhere in the band (palm_from_nearest_m, which
// keeps it near the nearest reading) both come back, so this can fail.
TEST(RandomScene, AnElbowNearerThanTheRaisedHandIsNotTakenForIt) {
  HandFinderParams nearest_is_hand;
  nearest_is_hand.arm_end_window_m = -1;
  nearest_is_hand.dome_significance = 0;
  nearest_is_hand.palm_from_nearest_m = 0;
  for (const std::uint64_t seed : {25u, 292u}) {
    const auto with_end = score_clip(random_scenario(seed));
    EXPECT_EQ(with_end.captured, 0u) << "seed " << seed;
    EXPECT_LE(with_end.rms_m, 0.01) << "seed " << seed;
    EXPECT_GE(with_end.tracked_ratio(), 0.8) << "seed " << seed;
    EXPECT_GT(score_clip(random_scenario(seed), nearest_is_hand).captured, 15u) << "seed " << seed;
  }
}

// Tuning seed 53: a user 0.8 m away, hand down; a second person walks behind at 1.7 m and their
// head is taken (no hand is raised: those are phantom frames, left open here). When the user
// raises the hand (0.62 m), the head, which is no arm's end, held the track, and after it was lost
// the jump test refused the hand: the hand was never tracked, RMS 1.19 m. A followed track that
// is no arm's end gives way to a component an arm's protrusion nearer that is one
// (take_over_by_arm_end); without it the head comes back, so this can fail.
// Seed 53's head is no longer taken (head_shoulders_half_m); the take-over is tested with that test off.
TEST(RandomScene, ARaisedHandTakesTheTrackFromASecondPersonsHead) {
  HandFinderParams take_over;
  take_over.head_shoulders_half_m = 0;
  const auto with_take_over = score_clip(random_scenario(53), take_over);
  EXPECT_GE(with_take_over.tracked_visible, 8u);
  EXPECT_LE(with_take_over.rms_m, 0.01);
  HandFinderParams no_take_over = take_over;
  no_take_over.take_over_by_arm_end = false;
  EXPECT_GT(score_clip(random_scenario(53), no_take_over).rms_m, 0.5);
}

// A head, an elbow or a shoulder's round end facing the sensor fills the depth band's disc as a palm
// does. Tuning seed 52: the hand down, a second person's head 1.7 m away was taken for 10 frames
// (RMS 195 mm). Seed 56 (session 35, the hanging world): a user 1.5 m away holds the hand above the
// image, and the elbow below it, 34 cm from the palm, was taken for 16 frames running. (On the floating
// world seeds 37, a shoulder's round end, and 64, the elbow of an arm rising from below, were the
// other cases; in the hanging world 37's is taken for 2 frames only and 64 has 3 frames captured by
// something else.) A new track does not start on a circle that bulges toward the sensor like a
// sphere (dome_significance); with the test off they are taken again, so this can fail.
TEST(RandomScene, AHeadOrAnElbowFacingTheSensorDoesNotStartATrack) {
  HandFinderParams no_dome_test;
  no_dome_test.dome_significance = 0;
  no_dome_test.head_shoulders_half_m = 0;  // seed 52's head has the second person's shoulders beneath it too
  for (const std::uint64_t seed : {52u, 56u}) {
    const auto with_test = score_clip(random_scenario(seed));
    EXPECT_EQ(with_test.captured, 0u) << "seed " << seed;
    EXPECT_LE(with_test.rms_m, 0.01) << "seed " << seed;
    EXPECT_GE(score_clip(random_scenario(seed), no_dome_test).longest_captured_run, 4u) << "seed " << seed;
  }
}

// Each seed's clip with nothing captured and within 1 cm, and a captured run of at least `run_without`
// with the rule under test switched off in `without`; `same_tracked`: the rule refuses no hand frame
// (as many visible frames tracked either way).
void expect_nothing_captured_but_a_run_without(std::initializer_list<std::uint64_t> seeds, const HandFinderParams& without,
                                               std::size_t run_without, bool same_tracked) {
  for (const std::uint64_t seed : seeds) {
    const auto with_rule = score_clip(random_scenario(seed));
    const auto without_rule = score_clip(random_scenario(seed), without);
    EXPECT_EQ(with_rule.captured, 0u) << "seed " << seed;
    if (same_tracked) {
      EXPECT_EQ(with_rule.tracked_visible, without_rule.tracked_visible) << "seed " << seed;
    }
    EXPECT_LE(with_rule.rms_m, 0.01) << "seed " << seed;
    EXPECT_GE(without_rule.longest_captured_run, run_without) << "seed " << seed;
  }
}

// A near user's upper arm or shoulder at the torso's depth is no hand. Tuning seeds 204 and 228 (session
// 37, the hanging world): users 0.77 and 0.95 m away lower the hand to hang; the upper arm, moving beside a
// torso that stood still, is foreground at the torso's depth and holds a palm-sized circle: it was taken
// as a new track and followed (runs of 14 and 8 captured frames). Half to two thirds of the ring 8-12 cm
// around its circle is the static torso at its depth, where a hand reaches out of what is behind it
// (body_surround_share); with the test off they are taken again, so this can fail.
TEST(RandomScene, AnUpperArmSetInTheTorsoDoesNotStartATrack) {
  HandFinderParams no_body_test;
  no_body_test.body_surround_share = 0;
  expect_nothing_captured_but_a_run_without({204u, 228u}, no_body_test, 8, true);
}

// Tuning seed 251 (session 38): a near user moves the hand out of the image's side; the upper
// arm, seen against the wall (no torso around it: body_surround_share does not refuse it), was
// refused as a new track from the foreground and taken again as its ridge flickered about
// max_palm_ridge_m (8.8-8.9 cm against 9), then followed: a run of 15 captured frames. A new track
// from the foreground holds its palm to max_foreground_new_palm_ridge_m (8 cm); with that at
// max_palm_ridge_m again the run comes back, so this can fail.
TEST(RandomScene, AnUpperArmAgainstTheWallDoesNotStartATrack) {
  HandFinderParams search_ridge;
  search_ridge.max_foreground_new_palm_ridge_m = search_ridge.max_palm_ridge_m;
  const auto with_test = score_clip(random_scenario(251));
  const auto without = score_clip(random_scenario(251), search_ridge);
  EXPECT_EQ(with_test.captured, 0u);
  EXPECT_EQ(with_test.tracked_visible, without.tracked_visible);  // the hand is not refused
  EXPECT_LE(with_test.rms_m, 0.01);
  EXPECT_GE(without.longest_captured_run, 12u);
}

// Tuning seed 146: a new track was measured at the arm's nearest reading unless that reading was
// also a joint (is_joint), and the arm was taken instead of the hand (RMS 68 mm over the clip). A new track from the foreground is now measured at
// the arm's geodesic end whenever the nearest reading lies on the way to it, as a followed one is;
// asking is_joint again brings the forearm back, so this can fail.
TEST(RandomScene, ANewTrackIsMeasuredAtTheArmsEndNotOnItsForearm) {
  const auto score = score_clip(random_scenario(146));
  EXPECT_LE(score.rms_m, 0.01);
  EXPECT_LE(score.longest_captured_run, 3u);
}

// Each seed's clip tracked (>= `tracked` of its visible frames, within 1 cm, nothing captured), and below
// `without_below` with the rule under test switched off in `without`.
void expect_tracked_but_not_without(std::initializer_list<std::uint64_t> seeds, double tracked, const HandFinderParams& without,
                                    double without_below) {
  for (const std::uint64_t seed : seeds) {
    const auto score = score_clip(random_scenario(seed));
    EXPECT_GE(score.tracked_ratio(), tracked) << "seed " << seed;
    EXPECT_LE(score.rms_m, 0.01) << "seed " << seed;
    EXPECT_EQ(score.captured, 0u) << "seed " << seed;
    EXPECT_LT(score_clip(random_scenario(seed), without).tracked_ratio(), without_below) << "seed " << seed;
  }
}

// Tuning seeds 34 and 285: a followed hand held 15-30 cm in front of the body; the depth band around its
// nearest reading took in the upper arm or the shoulder, whose wider circle was measured as the palm,
// 20-40 cm away, and the jump test refused it: the hand was lost for 27 % and 35 % of its visible
// frames (the hanging world, session 35; on the floating world seed 16 was the second, 35 %, which the
// hanging world's clip loses for 14 % only). A followed palm is sought near the hand's nearest reading
// (palm_from_nearest_m); sought anywhere in the band, the frames are lost again, so this can fail.
TEST(RandomScene, AFollowedPalmIsSoughtNearItsNearestReadingNotOnTheUpperArm) {
  HandFinderParams anywhere;
  anywhere.palm_from_nearest_m = 0;
  expect_tracked_but_not_without({34u, 285u}, 0.95, anywhere, 0.8);
}

// Tuning seed 87 (session 35, the hanging world; seed 113 on the floating world): the hand is lowered out
// of the image across its bottom edge; the followed component, the arm alone once the hand had gone, held a
// palm-sized place off the hand's course within the jump test's 20 cm of the last palm, and was followed for
// 13 frames, 28-50 cm above the hand. A followed palm must lie near where its last step carries it
// (max_off_course_m); without that test the arm is followed again, so this can fail.
TEST(RandomScene, AFollowedPalmThatLeavesItsCourseIsNotTheHand) {
  const auto score = score_clip(random_scenario(87));
  EXPECT_EQ(score.captured, 0u);
  EXPECT_GE(score.tracked_ratio(), 0.95);
  HandFinderParams no_course;
  no_course.max_off_course_m = 0;
  EXPECT_GT(score_clip(random_scenario(87), no_course).longest_captured_run, 3u);
}

// Tuning seeds 3, 65, 164 and 181 (session 43): a hand acquired a frame ago (by the search, within the
// background) moves on as foreground, and the followed component's palm was measured on its arm, 10-20 cm
// from the hand, its ridge running 10-14 cm along the arm: one captured frame each, then the track was lost.
// The track's second palm has no step to hold it to (off_course needs one), so a palm farther than
// max_unproven_step_m from the first must be palm-shaped as a new track's (radius, ridge, no dome, no
// shoulders); with that test off the frame is captured again, so this can fail. Fast hands whose second palm
// is palm-shaped are followed as before (seeds 41, 138, 259: 6-8 cm steps, ridges under 2 cm).
TEST(RandomScene, ATracksSecondPalmFarFromItsFirstIsPalmShaped) {
  HandFinderParams no_test;
  no_test.max_unproven_step_m = 0;
  expect_nothing_captured_but_a_run_without({3u, 65u, 164u, 181u}, no_test, 1, false);
  for (const std::uint64_t seed : {41u, 138u, 259u}) {
    EXPECT_EQ(score_clip(random_scenario(seed)).tracked_visible, score_clip(random_scenario(seed), no_test).tracked_visible)
        << "seed " << seed;
  }
}

// Tuning seeds 7 and 75: the hand is up and still from the first frame (so part of the background), with
// nearer things in the room; the nearest-first search used up its candidates on them, so the hand was found
// once and lost again, untracked for its first ~30 frames (64 % and 73 % of visible frames; now 99 % and
// 100 %), until it moved. A hand found last frame is tried first where it was (still_hand_m), and before any
// hand was seen more candidates are tried (start_candidates). With both as before, the frames are lost
// again, so this can fail. Captures are counted while the hand is raised: seed 75's user stands 2.3 m
// away and lowers the hand at the end; on the floating world (before session 35) it came to rest in view,
// detached from the arm, and the finder followed it there (11 frames). Hanging at the arm's end (the default
// since session 35) nothing is captured there; the test still counts only the raised hand's captures.
TEST(RandomScene, AHandHeldStillFromTheFirstFrameIsTrackedFromTheStart) {
  HandFinderParams as_before;
  as_before.still_hand_m = 0;
  as_before.start_candidates = as_before.candidates;
  for (const std::uint64_t seed : {7u, 75u}) {
    int captured_raised = 0;
    const auto still = score_clip(random_scenario(seed), {}, [&](const GroundTruth& truth, const HandObservation& hand) {
      if (truth.raised && hand.tracked && (hand.position_m.cast<double>() - truth.palm).norm() > kCaptureDistanceM) ++captured_raised;
    });
    EXPECT_GE(still.tracked_ratio(), 0.95) << "seed " << seed;
    EXPECT_LE(still.rms_m, 0.01) << "seed " << seed;
    EXPECT_EQ(captured_raised, 0) << "seed " << seed;
    EXPECT_LT(score_clip(random_scenario(seed), as_before).tracked_ratio(), 0.8) << "seed " << seed;
  }
}

// Tuning seed 86: the hand is held up beside the head from the first frame, its forearm and upper arm at
// its depth; a new track's band took them in and its widest place was the elbow, a tube refused by the
// ridge test, so the hand was untracked for its first 15 frames and again for 11 (65 % of visible frames,
// now 97.5 %; the hanging world, the default since session 35: 54 of 82 without the look, 80 with it).
// Such a candidate is looked at again near its nearest reading (second_look_near_nearest); without that
// look the frames are lost again, so this can fail.
TEST(RandomScene, AHandHeldUpWithItsArmAtItsDepthIsFoundAtItsFingertipsNotTheElbow) {
  HandFinderParams first_look_only;
  first_look_only.second_look_near_nearest = false;
  const auto score = score_clip(random_scenario(86));
  EXPECT_GE(score.tracked_ratio(), 0.95);
  EXPECT_LE(score.rms_m, 0.01);
  EXPECT_EQ(score.captured, 0u);
  EXPECT_LT(score_clip(random_scenario(86), first_look_only).tracked_ratio(), 0.8);
}

// Tuning seeds 196 and 495: a far user raises the hand beside the head with the elbow held forward, 1 cm
// behind the hand's nearest reading; the search without a background measured the band's widest place,
// the elbow 35-40 cm below the hand, and took it (captured runs of 2 and 4 frames, 31-33 cm off). A new
// track's palm lies within a hand's length of the candidate's nearest reading
// (max_new_palm_from_nearest_m); farther, the palm is sought near that reading instead. Without the limit
// the elbow is taken again, so this can fail.
TEST(RandomScene, APalmFarFromTheCandidatesNearestReadingIsNotItsHand) {
  HandFinderParams no_limit;
  no_limit.max_new_palm_from_nearest_m = 0;
  for (const std::uint64_t seed : {196u, 495u}) {
    SCOPED_TRACE(seed);
    EXPECT_EQ(score_clip(random_scenario(seed)).captured, 0u);
    EXPECT_GE(score_clip(random_scenario(seed), no_limit).longest_captured_run, 2u);
  }
  EXPECT_LE(score_clip(random_scenario(196)).rms_m, 0.01);
}

// Tuning seed 138: a near user raises the hand in front of a second person's head, fingertips leaning
// toward the camera as near as the elbow pointing at it. The hand is the arm's geodesic end, reached from
// the elbow (arm_end); is_joint asked there walked from the fingertips down the forearm, over the elbow
// and onto the upper arm behind it, and counted that as the hand's second limb: the hand was refused as a
// new track for 14 frames (16 of 55 visible frames tracked). The walk no longer goes back over the joint
// the end was reached from.
TEST(RandomScene, AHandReachedFromItsElbowIsNotAJointThroughThatElbow) {
  const auto score = score_clip(random_scenario(138));
  EXPECT_GE(score.tracked_visible, 28u);
  EXPECT_LE(score.rms_m, 0.01);
  EXPECT_EQ(score.captured, 0u);
}

// A hand that moves on within the background. Tuning seed 207: a hand held still at 2 m from the first
// frame (so part of the background) was lost for its last 90 frames when a table edge entered the image's
// corner (the refused table's palm, not the hand's, was where the still hand was sought) and, once it
// began to push toward the camera at 1-2 cm a frame, by the still-hand test (26 % of visible frames).
// Seed 298: a followed hand 10 cm before the chest, too near the body to be foreground, was lost at its
// first step (27 %). The hand is now sought where it was last reported and taken where it was or where its
// last step carries it (91 % and 76 %).
TEST(RandomScene, AHandThatMovesOnWithinTheBackgroundIsStillFollowed) {
  const auto pushed = score_clip(random_scenario(207));
  EXPECT_GE(pushed.tracked_ratio(), 0.85);
  EXPECT_LE(pushed.rms_m, 0.01);
  EXPECT_EQ(pushed.captured, 0u);
  const auto before_chest = score_clip(random_scenario(298));
  EXPECT_GE(before_chest.tracked_ratio(), 0.7);
  EXPECT_LE(before_chest.rms_m, 0.01);
  EXPECT_EQ(before_chest.captured, 0u);
}

// Tuning seed 156: the user reaches out of the image's side, the arm level with the shoulder; the shoulder's
// junction with the arm held a palm-sized place whose surface runs back, and once the arm's nearest reading
// left the border it was taken as a new track and followed for 48 frames, 30 cm from the hand, out of view.
// A new track's front surface (within 2 cm of its nearest reading) may meet the border only within a hand's
// reach of its palm (fingers cut by the border, as in seed 10: a user at 0.67 m whose fingers leave the
// top), not farther (an arm running out of the image). Seed 48: the user's other arm, hanging, its forearm
// running out of the image's bottom, taken for 6 frames while no hand was raised.
TEST(RandomScene, AnArmThatRunsOutOfTheImageIsNotTakenForAHandButFingersThatDoAre) {
  HandFinderParams no_border_test;
  no_border_test.front_in_view_beyond_hand = false;
  no_border_test.body_surround_share = 0;  // seed 48's hanging forearm is set in the torso at its depth too (session 37)
  for (const std::uint64_t seed : {156u, 48u}) {
    EXPECT_EQ(score_clip(random_scenario(seed)).captured, 0u) << "seed " << seed;
    EXPECT_GT(score_clip(random_scenario(seed), no_border_test).longest_captured_run, 3u) << "seed " << seed;
  }
  const auto fingers_cut = score_clip(random_scenario(10));
  EXPECT_GE(fingers_cut.tracked_ratio(), 0.95);
  EXPECT_LE(fingers_cut.rms_m, 0.01);
}

// Tuning seed 6: a user 2.3 m away raises the hand and holds it 2.19 m from the camera. One raw unit of
// disparity is 1.5 cm there, so the forearm running back from the hand (1.5 cm between grid cells) reads in
// steps of 3 cm and more between neighbours, and the surface walk that asks whether the hand is an arm's
// end (22 cm back beyond 1.8 m) broke on them: the hand was refused as a new track for 26 frames, 19 of
// them held still (89 of 117 visible frames tracked). The walk now allows three of the Kinect's depth steps
// where that is more than 3 cm (109 of 117).
TEST(RandomScene, AFarUsersForearmIsOneSurfaceAtTheKinectsDepthSteps) {
  const auto score = score_clip(random_scenario(6));
  EXPECT_GE(score.tracked_ratio(), 0.9);
  EXPECT_LE(score.rms_m, 0.01);
  EXPECT_EQ(score.captured, 0u);
  HandFinderParams three_cm;
  three_cm.surface_step_quanta = 0;
  EXPECT_LT(score_clip(random_scenario(6), three_cm).tracked_ratio(), 0.8);
}

TEST(RandomScene, AHeadWithShouldersBeneathItIsNotTakenForAHand) {
  // A second person walking behind the user: the head (a palm-sized round face at the depth of the
  // shoulders below it) started a track before the user's hand was raised (seed 320: never raised,
  // 21 frames; seed 459: 8 frames). The user's hand, raised later, is still found.
  HandFinderParams no_head_test;
  no_head_test.head_shoulders_half_m = 0;
  for (const std::uint64_t seed : {320u, 459u}) {
    const auto with = score_clip(random_scenario(seed));
    EXPECT_LE(with.longest_captured_run, 1u) << "seed " << seed;
    EXPECT_GT(score_clip(random_scenario(seed), no_head_test).longest_captured_run, 3u) << "seed " << seed;
  }
  EXPECT_GE(score_clip(random_scenario(459)).tracked_ratio(), 0.8);
}

// The jump test after a glimpse (jump_from_kept_course): a lost hand does not reappear farther than
// max_jump_m from the last palm that kept its course; a one- or two-frame track since does not hold it
// away. Tuning seed 80 (session 35, the hanging world): as the hand rises from the hanging arm, still below
// the image, a place on the arm 16 cm off it is taken for one frame (32); measured from there the hand
// itself was refused for the next 15 frames (28 of 43 visible frames tracked; with the test 41). Seed 181,
// a user 1 m away, the same on its rise (the arm 21 cm off at frame 35): 28 of 44 without the test, 42
// with it. (On the floating world seeds 4 and 139 showed it, 14 and 15 frames; in the hanging world their
// clips track the same frames without the test, 50 of 53 and 47 of 47.) Measured from the last palm
// whatever it was (jump_from_kept_course false), the frames are lost again, so this can fail. Session 41's
// max_new_palm_behind_nearest_m refuses seed 80's glimpse itself (its one captured frame gone, 41 -> 42
// tracked): for 80 the rule-off half lets the glimpse in too (that test at 0), as it was when this was written.
// Session 43's max_unproven_step_m refuses seed 181's glimpse (the track's second palm, on the arm): for 181
// the rule-off half sets it to 0.
TEST(RandomScene, AGlimpseOfTheHandDoesNotHoldItAwayAfterwards) {
  HandFinderParams from_last_palm;
  from_last_palm.jump_from_kept_course = false;
  HandFinderParams glimpse_let_in_80 = from_last_palm;
  glimpse_let_in_80.max_new_palm_behind_nearest_m = 0;
  glimpse_let_in_80.max_new_palm_from_nearest_m = 0;  // session 47's limit refuses that glimpse too
  HandFinderParams glimpse_let_in_181 = from_last_palm;
  glimpse_let_in_181.max_unproven_step_m = 0;
  for (const std::uint64_t seed : {80u, 181u}) {
    const auto score = score_clip(random_scenario(seed));
    EXPECT_GE(score.tracked_ratio(), 0.9) << "seed " << seed;
    EXPECT_LE(score.longest_captured_run, 1u) << "seed " << seed;
    const auto& without = seed == 80u ? glimpse_let_in_80 : glimpse_let_in_181;
    EXPECT_LT(score_clip(random_scenario(seed), without).tracked_ratio(), 0.75) << "seed " << seed;
  }
}

// The border-cut test against the hand's own palm (own_palm_shrink_m): a followed palm turned 15-30 degrees
// from the line of sight holds a 3.6-3.9 cm circle, under the fixed whole palm's 3.9 cm, and with its fingers
// or wrist across the image border it was refused as cut though its circle was within 2 cm of the truth.
// The hanging world (session 35): tuning seed 507, 89 of 109 visible frames tracked without the test, 106
// with it; seed 38, 97 of 103, 100 with it. (On the floating world seeds 241 and 188 showed it.)
TEST(RandomScene, AFollowedPalmAsLargeAsItsOwnIsNotCutByTheBorder) {
  HandFinderParams fixed_size_only;
  fixed_size_only.own_palm_shrink_m = 0;
  expect_tracked_but_not_without({507u, 38u}, 0.97, fixed_size_only, 0.95);
}

// The randomized world's resting pose (docs/sensor.md, sessions 34 and 35). Floating (the previous world,
// random_scenario(seed, false): 0.72 m below the shoulder, beyond the arm's reach), a far user's lowered hand
// hangs in view detached from the arm, and the finder follows it down there, scored captured because it is
// not raised: tuning seeds 51, 75 and 91 (users 2.1-2.5 m away), runs of 10-12 frames. Hanging at the arm's
// end, fingers down (random_scenario's default since session 35), the same clips have nothing captured.
TEST(RandomScene, AHandRestingAtTheArmsEndIsNotFollowedDownToAFloatingPose) {
  for (const std::uint64_t seed : {51u, 75u, 91u}) {
    EXPECT_GE(score_clip(random_scenario(seed, false)).longest_captured_run, 10u) << "seed " << seed;
    const auto hanging = score_clip(random_scenario(seed));
    EXPECT_EQ(hanging.captured, 0u) << "seed " << seed;
    EXPECT_GE(hanging.tracked_ratio(), 0.95) << "seed " << seed;
  }
}

// The course across a gap (course_gap_frames). Tuning seed 24 with the hanging rest: a user 1 m away lowers the
// hand out of the image's bottom with the arm attached; the hand is missed a frame at the border (86), and the
// next three frames a palm-sized place on the forearm, 31-43 cm above where the hand went, was followed (within
// max_jump_m of the last palm, and with no course known across the missed frame). A palm found again within 4
// frames must lie where the last kept step carries the hand; without that test the forearm is followed again,
// so this can fail.
TEST(RandomScene, AForearmLeftInViewWhenTheHandGoesDownIsNotFollowedAcrossAMissedFrame) {
  const auto score = score_clip(random_scenario(24, true));
  EXPECT_EQ(score.captured, 0u);
  EXPECT_GE(score.tracked_ratio(), 0.95);
  HandFinderParams consecutive_only;
  consecutive_only.course_gap_frames = 0;
  EXPECT_GE(score_clip(random_scenario(24, true), consecutive_only).longest_captured_run, 3u);
}

// Tuning seeds 15 and 160 (sessions 35, 39, 40): a thing slid in from the side and stopped nearer than
// the hand (0.66 and 0.76 m, the hand last seen at 1.55 and 1.70 m); measured and refused as a new track
// every frame, it was kept from the background's learning, never learned, and the hand behind it was
// never measured (21 of 108 and 0 of 67 visible frames tracked). A thing refused as a new track that
// has come to rest (rest_frames, rest_share), nearer than the hand was last seen by
// rest_nearer_than_hand_m, is learned; with rest_frames = 0 it is not, so this can fail.
TEST(RandomScene, AThingThatCameToRestNearerThanTheHandBecomesBackground) {
  HandFinderParams no_rest;
  no_rest.rest_frames = 0;
  for (const std::uint64_t seed : {15u, 160u}) {
    const auto with_rule = score_clip(random_scenario(seed));
    const auto without = score_clip(random_scenario(seed), no_rest);
    EXPECT_GE(with_rule.tracked_ratio(), 0.65) << "seed " << seed;
    EXPECT_LE(with_rule.rms_m, 0.01) << "seed " << seed;
    EXPECT_LT(without.tracked_ratio(), 0.25) << "seed " << seed;
  }
}

// Tuning seed 133 (session 40): the user follows the hand out of the image's side with a step and
// pauses there, the hand out of view; the whole user, refused as a new track, comes to rest at the
// hand's depth. Learned into the background, the arm moved out of it when the user stepped back and was
// taken 29 cm from the hand (one captured frame, RMS 11.3 -> 35.7 mm). A hand that pauses is at rest
// too: nothing at rest within rest_nearer_than_hand_m of the hand's last depth (or behind it) is learned;
// with that condition off the arm is taken again, so this can fail.
TEST(RandomScene, AUserWhoPausedAtTheHandsDepthIsNotLearnedIntoTheBackground) {
  HandFinderParams any_depth;
  any_depth.rest_nearer_than_hand_m = -10;
  const auto with_rule = score_clip(random_scenario(133));
  const auto without = score_clip(random_scenario(133), any_depth);
  EXPECT_EQ(with_rule.captured, 0u);
  EXPECT_GE(without.captured, 1u);
}

// Seeds 73 (tuning) and 497 (check), session 41: the search without a background refuses the hand (too
// near the image's bottom, 73) or has lost it (swung down fast, 497) and tries the nearest readings behind
// it, on its forearm; that candidate's palm, measured in its own plane, follows the plane of the arm running
// back and lands on the forearm or upper arm 10-19 cm behind the candidate's nearest reading, 16-31 cm from
// the hand (runs of 5 and 4 captured frames). A new track's palm lies no more than
// max_new_palm_behind_nearest_m (0.10) behind its nearest reading; with that test off (0) the runs come
// back, so this can fail. (307's palm, 7.9 cm behind, is under 0.10; 407 keeps one captured frame.)
TEST(RandomScene, APalmMeasuredOnTheArmBehindTheCandidateDoesNotStartATrack) {
  HandFinderParams any_depth;
  any_depth.max_new_palm_behind_nearest_m = 0;
  any_depth.max_new_palm_from_nearest_m = 0;  // since session 47 that palm is too far from the reading as well (497)
  // The captured frames were counted as tracked: fewer tracked frames with the rule, not the same.
  expect_nothing_captured_but_a_run_without({73u, 497u}, any_depth, 4, false);
}

// Tuning seed 307 (session 41's check range): the hand held still before the chest at 1.27 m from the
// first frame (part of the background) is refused by the search as no arm's end (its surface does not
// run arm_protrusion_m back); the next candidate, its forearm at 1.40 m, whose band holds that hand,
// reaches back and was measured as a turned palm on the upper arm at 1.48 m, 25 cm from the hand: a run
// of 15 captured frames (23 in all). A search candidate whose band holds a palm refused nearer as no
// arm's end, measured elsewhere than that palm, is its arm (refuse_arm_of_refused_palm); with that off
// the run comes back, so this can fail. The frames tracked on the hand (within 10 cm) are as many
// either way: the rule refuses the arm, not the hand. Since session 46 the hanging-hand rule
// (max_palm_tips_down) refuses part of that arm's placed palms too: without this rule alone the run
// is 4 frames, without both the 15 again.
TEST(RandomScene, TheArmOfAPalmRefusedNearerInTheSearchDoesNotStartATrack) {
  HandFinderParams off;
  off.refuse_arm_of_refused_palm = false;
  HandFinderParams neither = off;
  neither.max_palm_tips_down = 2;  // > 1: no such test
  const auto on_hand = [](const HandFinderParams& params, ClipScore& score) {
    std::size_t frames = 0;
    score = score_clip(random_scenario(307), params, [&](const GroundTruth& truth, const HandObservation& hand) {
      if (truth.visible && hand.tracked && (hand.position_m.cast<double>() - truth.palm).norm() <= 0.10) ++frames;
    });
    return frames;
  };
  ClipScore with_rule, without_rule;
  const std::size_t with_on_hand = on_hand({}, with_rule), without_on_hand = on_hand(off, without_rule);
  EXPECT_LE(with_rule.longest_captured_run, 1u);
  EXPECT_LE(with_rule.captured, 1u);
  EXPECT_GE(with_on_hand, without_on_hand);
  EXPECT_GT(without_rule.longest_captured_run, 3u);
  EXPECT_GE(score_clip(random_scenario(307), neither).longest_captured_run, 15u);
}

TEST(ClipScore, CapturedIsFarFromTheHandOrAnyPointWhenNoHandIsRaised) {
  ClipScore score;
  std::size_t run = 0;
  double sum = 0;
  GroundTruth up;
  up.raised = up.visible = true;
  up.palm = {0, 0, 1};
  GroundTruth down;  // hanging: not raised
  down.palm = {0, 0.7, 1.4};
  score_frame(at({0, 0, 1.005}), up, score, run, sum);   // 5 mm off: fine
  score_frame(at({0, 0.15, 1}), up, score, run, sum);    // 15 cm off: captured
  score_frame(at({0, 0.7, 1.4}), down, score, run, sum); // on the hanging hand: captured all the same (and a phantom)
  score_frame(at({0, 0.7, 1.4}), down, score, run, sum);
  score_frame(HandObservation{}, down, score, run, sum); // nothing: the run ends
  score_frame(at({0, 0.7, 1.4}), down, score, run, sum);
  EXPECT_EQ(score.frames, 6u);
  EXPECT_EQ(score.visible, 2u);
  EXPECT_EQ(score.tracked_visible, 2u);
  EXPECT_EQ(score.phantoms, 3u);
  EXPECT_EQ(score.captured, 4u);
  EXPECT_EQ(score.longest_captured_run, 3u);
  EXPECT_NEAR(score.rms_m, std::sqrt((0.005 * 0.005 + 0.15 * 0.15) / 2), 1e-6);
}

TEST(ClipScore, AHandReportedWhereItIsWhileRisingIsNoPhantom) {
  ClipScore score;
  std::size_t run = 0;
  double sum = 0;
  GroundTruth rising;
  rising.raised = rising.rising = true;
  rising.palm = {0, 0.5, 1.3};
  score_frame(at({0, 0.51, 1.3}), rising, score, run, sum);
  EXPECT_EQ(score.phantoms, 0u);
  EXPECT_EQ(score.captured, 0u);
  score_frame(at({0, 0.1, 1.3}), rising, score, run, sum);  // 40 cm off: captured, and a phantom
  EXPECT_EQ(score.phantoms, 1u);
  EXPECT_EQ(score.captured, 1u);
}

// Session 44: a palm turned 24-49 degrees about the vertical, either way (tuning seeds 12, 17, 110, 125),
// shows the hand's side beside its face, and the silhouette's widest place lay 5-8 mm along the turn from
// the palm's centre (mean error along x, signed with the turn; 64 of the 66 clips on seeds 1-300 turned 15
// degrees or more leaned the same way). The face's centre (report_palm_face) takes that lean out; with the
// silhouette's reported again it comes back, so this can fail. Frontal palms 2 m away (seeds 33 and
// 165), where a 1 cm band around the palm's plane frayed the face between Kinect's 13 mm depth steps
// and its circle wandered 1-3 cm, must not lose to the silhouette.
TEST(RandomScene, ATurnedPalmIsReportedAtItsFaceNotBesideIt) {
  HandFinderParams silhouette;
  silhouette.report_palm_face = false;
  const auto lean_along_turn = [](std::uint64_t seed, const HandFinderParams& params) {
    const ScenarioSpec spec = random_scenario(seed);
    const double turn = spec.palm_yaw_deg > 0 ? 1.0 : -1.0;
    double sum = 0;
    int count = 0;
    score_clip(spec, params, [&](const GroundTruth& truth, const HandObservation& hand) {
      if (!truth.visible || !hand.tracked) return;
      sum += turn * (hand.position_m.x() - truth.palm.x());
      ++count;
    });
    return count > 0 ? sum / count : 1.0;
  };
  for (const std::uint64_t seed : {12u, 17u, 110u, 125u}) {
    const double face = lean_along_turn(seed, {}), side = lean_along_turn(seed, silhouette);
    EXPECT_LT(std::abs(face), 0.0025) << "seed " << seed;
    EXPECT_GT(side, 0.004) << "seed " << seed;
  }
  for (const std::uint64_t seed : {33u, 165u})
    EXPECT_LE(score_clip(random_scenario(seed)).rms_m, score_clip(random_scenario(seed), silhouette).rms_m + 0.0005) << "seed " << seed;
}

// Seed 66: a hand 0.67 m away, held still long enough to be learnt into the background, then moving
// on: the foreground held only its fingers, whose block (a 3.3 cm circle, over the 3.2 cm a palm
// needs) was measured 6 cm above the palm in five frames. A circle smaller than a whole palm in a
// region the ROI cut is measured again in a grown ROI, and the palm's larger circle taken where it
// adjoins the small one: in seed 369 the grown ROI's band held a larger circle 30 cm from the hand.
TEST(RandomScene, AStillHandsFingersAloneInTheForegroundAreNotTakenForItsPalm) {
  const auto score = score_clip(random_scenario(66));
  EXPECT_LT(score.max_m, 0.02);
  EXPECT_EQ(score.tracked_visible, score.visible);
  EXPECT_EQ(score_clip(random_scenario(369)).captured, 0);
}

// A palm seen nearly edge-on is placed by the hand's shape (measure_edge_on_palm), a palm's half width
// in from its far edge. The thumb stands out beside the palm on the far side when the palm turns away
// from it (seeds 48, 84, 138: right hands turned ~52 degrees that way) and on the near side when it
// turns toward it (259, 296). The whole palm's far edge was then the thumb's, and those placed frames
// lay 3-4 cm off (33 mm RMS); slice by slice along the palm it is the palm's own edge, whichever side
// the thumb is on. Placed frames are told by the model's radius and half confidence.
TEST(RandomScene, AnEdgeOnPalmIsPlacedFromThePalmsEdgeNotItsThumbs) {
  const auto placed_rms = [](std::initializer_list<std::uint64_t> seeds) {
    const auto placed_radius = static_cast<float>(HandFinderParams{}.palm_radius_m);
    double sum = 0;
    int count = 0;
    for (const std::uint64_t seed : seeds)
      score_clip(random_scenario(seed), {}, [&](const GroundTruth& truth, const HandObservation& hand) {
        if (!truth.visible || !hand.tracked || hand.palm_radius_m != placed_radius || hand.confidence > 0.5f) return;
        sum += (hand.position_m.cast<double>() - truth.palm).squaredNorm();
        ++count;
      });
    return std::pair{count, std::sqrt(sum / std::max(1, count))};
  };
  const auto [thumb_far, thumb_far_rms] = placed_rms({48, 84, 138});
  EXPECT_GE(thumb_far, 15);
  EXPECT_LT(thumb_far_rms, 0.012);
  const auto [thumb_near, thumb_near_rms] = placed_rms({259, 296});
  EXPECT_GE(thumb_near, 40);
  EXPECT_LT(thumb_near_rms, 0.012);
  // Seed 990: a hand 1.76 m away whose region ran, in the palm's edge-on plane, into what is behind;
  // its "far edge" there put the centre 22-25 cm behind the hand (across the palm is nearly along the
  // line of sight there). A centre farther than a palm's half width from the hand's axis is not placed.
  // (Its other placed frames err along the hand, up to 18 cm, by 10 cm at most in depth.)
  double deepest = 0;
  score_clip(random_scenario(990), {}, [&](const GroundTruth& truth, const HandObservation& hand) {
    if (hand.tracked && hand.palm_radius_m == static_cast<float>(HandFinderParams{}.palm_radius_m) && hand.confidence <= 0.5f)
      deepest = std::max(deepest, std::abs(hand.position_m.z() - truth.palm.z()));
  });
  EXPECT_LT(deepest, 0.15);
}

// A hand hanging at rest beside the body is seen edge-on with its fingers down, and it reaches out of
// the surface behind it as a raised hand does: seeds 68, 200, 263 and 272 took it as a new track while
// it was not raised (captured runs of 1-6 frames; 200: a user 1.78 m away who lowered the hand), and 186
// followed a lowered hand into its rest. No edge-on palm whose fingers point more than 45 degrees down is
// reported; without the rule each of these clips has captured frames, with it none.
TEST(RandomScene, AHandHangingAtRestIsNoPalm) {
  HandFinderParams without;
  without.max_palm_tips_down = 2;  // > 1: no such test
  for (const std::uint64_t seed : {68, 186, 200, 263, 272}) {
    SCOPED_TRACE(seed);
    EXPECT_GT(score_clip(random_scenario(seed), without).captured, 0);
    const auto score = score_clip(random_scenario(seed));
    EXPECT_EQ(score.captured, 0);
    EXPECT_EQ(score.phantoms, 0);
  }
}

TEST(Summary, FailsOnEachRateItMisses) {
  ClipScore good;
  good.visible = good.tracked_visible = 100;
  good.rms_m = 0.004;
  std::vector<ClipScore> clips(40, good);
  EXPECT_TRUE(summarize(clips).passed);
  auto bad_rms = clips;
  bad_rms[0].rms_m = bad_rms[1].rms_m = bad_rms[2].rms_m = 0.02;  // 37 of 40 = 92.5% < 97%
  EXPECT_FALSE(summarize(bad_rms).passed);
  auto untracked = clips;
  untracked[0].tracked_visible = 50;  // 3950 of 4000 = 98.75% < 99%
  EXPECT_FALSE(summarize(untracked).passed);
  auto phantom = clips;
  phantom[3].phantoms = 1;
  EXPECT_FALSE(summarize(phantom).passed);
  auto captured = clips;
  captured[5].captured = captured[5].longest_captured_run = 4;
  EXPECT_FALSE(summarize(captured).passed);
  captured[5].captured = captured[5].longest_captured_run = 3;
  EXPECT_TRUE(summarize(captured).passed);
  const auto s = summarize(bad_rms);
  EXPECT_NEAR(s.p95_rms_m, 0.02, 1e-12);  // nearest rank: the 38th of 40 sorted values
  EXPECT_NEAR(summarize(clips).p95_rms_m, 0.004, 1e-12);
  ASSERT_EQ(s.failures.size(), 1u);
}

}  // namespace
}  // namespace tachi::sensor
