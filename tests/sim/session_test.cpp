#include "tachi/sim/session.hpp"

#include <gtest/gtest.h>

#include <limits>

using namespace tachi::sim;

namespace {
SessionOptions small_cloth() {
  SessionOptions options;
  options.cloth.columns = options.cloth.rows = 16;
  options.cloth.pin = PinMode::TopEdge;
  return options;
}
HandInput hand(std::uint32_t stroke, double t, float x, float y, bool cutting) {
  return {stroke, t, {x, y, 0.0f}, true, cutting};
}
// A left-to-right sweep across the whole cloth at height y, starting and ending outside it.
void sweep(Session& session, std::uint32_t stroke, float y, double t0) {
  for (int i = 0; i <= 40; ++i) session.on_hand(hand(stroke, t0 + i * 0.01, -0.7f + 1.4f * static_cast<float>(i) / 40.0f, y, true));
}
}  // namespace

TEST(Session, IdleHandNeitherCutsNorReports) {
  Session session{small_cloth()};
  for (int i = 0; i < 10; ++i) session.on_hand(hand(0, i * 0.01, 0.0f, 0.0f, false));
  session.step();
  EXPECT_FALSE(session.take_topology_change());
  EXPECT_TRUE(session.take_cut_reports().empty());
}

TEST(Session, AFullWidthStrokeCutsOffTheLowerPieceWhenTheGateCloses) {
  Session session{small_cloth()};
  const auto version_before = session.cloth().topology_version;
  sweep(session, 1, -0.1f, 0.0);
  EXPECT_TRUE(session.take_cut_reports().empty()) << "no report while the stroke is open";
  session.on_hand(hand(1, 0.5, 0.7f, -0.1f, false));  // gate closes
  const auto reports = session.take_cut_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].stroke_id, 1u);
  EXPECT_EQ(reports[0].pieces, 2u);
  EXPECT_EQ(reports[0].fallen_pieces, 1u);
  EXPECT_GT(reports[0].stroke.particles_duplicated, 0u);
  const auto change = session.take_topology_change();
  ASSERT_TRUE(change);
  EXPECT_GT(change->version, version_before);
  EXPECT_EQ(change->particle_count_before, 16u * 16u);
  EXPECT_EQ(session.cloth().particle_count(), 16u * 16u + change->duplicated_from.size());
  EXPECT_FALSE(session.take_topology_change()) << "a change is handed out once";
}

TEST(Session, ANewStrokeIdClosesTheOpenStroke) {
  Session session{small_cloth()};
  sweep(session, 1, 0.2f, 0.0);
  sweep(session, 2, -0.2f, 1.0);
  session.end_stroke();
  const auto reports = session.take_cut_reports();
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0].stroke_id, 1u);
  EXPECT_EQ(reports[1].stroke_id, 2u);
  EXPECT_EQ(reports[1].pieces, 3u);
}

TEST(Session, HoldingSamplesKeepTheStrokeOpenWithoutCutting) {
  Session session{small_cloth()};
  for (int i = 0; i <= 10; ++i) session.on_hand(hand(1, i * 0.01, -0.7f + 0.07f * static_cast<float>(i), 0.0f, true));
  const auto cut_before = session.cutter().report().cut_line;
  // The hand leaves downwards while the gate waits out its exit dwell: nothing may be cut there.
  for (int i = 1; i <= 4; ++i) {
    HandInput leaving = hand(1, 0.2 + i * 0.01, 0.0f, -0.1f * static_cast<float>(i), false);
    leaving.holding = true;
    session.on_hand(leaving);
  }
  EXPECT_TRUE(session.cutter().stroke_open());
  EXPECT_EQ(session.cutter().report().cut_line.size(), cut_before.size());
  session.on_hand(hand(1, 0.3, 0.0f, -0.4f, false));
  const auto reports = session.take_cut_reports();
  ASSERT_EQ(reports.size(), 1u);
  for (const auto& g : reports[0].stroke.cut_line) EXPECT_LE(std::abs(g.v - 8), 1) << "cut strayed to row " << g.v;
}

TEST(Session, LostOrNonFiniteSamplesNeverCutButTheGateStillClosesTheStroke) {
  Session session{small_cloth()};
  session.on_hand(hand(1, 0.0, -0.7f, 0.0f, true));
  session.on_hand({1, 0.01, {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f}, true, true});
  session.on_hand({1, 0.02, {0.3f, 0.0f, 0.0f}, false, true});  // lost while the gate is still open
  EXPECT_TRUE(session.cutter().stroke_open());
  EXPECT_TRUE(session.cutter().report().cut_line.size() <= 2u) << "nothing cut toward the unseen samples";
  EXPECT_TRUE(session.take_cut_reports().empty());
  session.on_hand({1, 0.03, {0.0f, 0.0f, 0.0f}, false, false});  // the gate closes on a lost hand
  EXPECT_FALSE(session.cutter().stroke_open());
  EXPECT_EQ(session.take_cut_reports().size(), 1u);
}

TEST(Session, TheIdleHandPushesTheClothAsAColliderSphere) {
  auto options = small_cloth();
  options.hand_radius_m = 0.1f;
  Session session{options};
  for (int i = 0; i < 30; ++i) {
    session.on_hand(hand(0, i / 60.0, 0.0f, -0.2f, false));
    session.step();
  }
  for (const auto& p : session.cloth().position)
    EXPECT_GE((p - Eigen::Vector3f(0.0f, -0.2f, 0.0f)).norm(), 0.1f - 1e-3f);
}

TEST(Session, StrokesOfTwoHandSourcesAreToldApartBySensorAndSession) {
  Session session{small_cloth()};
  const auto from = [](HandInput h, std::uint32_t sensor, std::uint64_t run) {
    h.sensor_id = sensor;
    h.session_id = run;
    return h;
  };
  // The mouse blade (sensor 1000) cuts its stroke 1 while the camera hand (sensor 1) idles in front of
  // the cloth: the camera's idle samples must not close the mouse's stroke.
  for (int i = 0; i <= 40; ++i) {
    session.on_hand(from(hand(1, i * 0.01, -0.7f + 1.4f * static_cast<float>(i) / 40.0f, -0.1f, true), 1000, 5));
    session.on_hand(from(hand(0, i * 0.01, 0.2f, 0.3f, false), 1, 9));
  }
  EXPECT_TRUE(session.take_cut_reports().empty()) << "the mouse's stroke is still open";
  session.on_hand(from(hand(1, 0.5, 0.7f, -0.1f, false), 1000, 5));
  auto reports = session.take_cut_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].sensor_id, 1000u);
  EXPECT_EQ(reports[0].pieces, 2u);

  // The camera's own stroke 1 is another stroke than the mouse's stroke 1.
  for (int i = 0; i <= 40; ++i)
    session.on_hand(from(hand(1, 1.0 + i * 0.01, -0.7f + 1.4f * static_cast<float>(i) / 40.0f, 0.2f, true), 1, 9));
  session.on_hand(from(hand(1, 1.5, 0.7f, 0.2f, false), 1, 9));
  reports = session.take_cut_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].sensor_id, 1u);
  EXPECT_GT(reports[0].stroke.particles_duplicated, 0u);
}
