#include "tachi/viewer/scene_state.hpp"

#include <gtest/gtest.h>

using namespace tachi::viewer;

TEST(SceneState, StatusSaysWhatIsMissing) {
  SceneState state;
  EXPECT_NE(state.scene().status.find("waiting for the cloth topology"), std::string::npos);
  state.on_topology({1, {{0, 1, 2}}, {}});
  EXPECT_NE(state.scene().status.find("waiting for cloth positions"), std::string::npos);
  state.on_state({7, 1, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}});
  EXPECT_TRUE(state.has_cloth());
  EXPECT_NE(state.scene().status.find("frame 7"), std::string::npos);
}

TEST(SceneState, AnOlderTopologyArrivingLateIsIgnored) {
  SceneState state;
  state.on_topology({3, {{0, 1, 2}, {1, 2, 3}}, {}});
  state.on_topology({2, {{0, 1, 2}}, {}});
  EXPECT_EQ(state.scene().mesh.topology_version, 3u);
  EXPECT_EQ(state.scene().mesh.triangles.size(), 2u);
}

// Issue 13: a restarted simulator counts versions from 1 again; its new session is followed.
TEST(SceneState, ARestartedSimulatorsNewSessionIsFollowedWhateverItsVersion) {
  SceneState state;
  state.on_topology({30, {{0, 1, 2}, {1, 2, 3}}, {}, 111});
  state.on_topology({1, {{0, 1, 2}}, {}, 222});
  EXPECT_EQ(state.scene().mesh.topology_version, 1u);
  EXPECT_EQ(state.scene().mesh.triangles.size(), 1u);
  state.on_topology({29, {{0, 1, 2}, {1, 2, 3}}, {}, 222});
  state.on_topology({5, {{0, 1, 2}}, {}, 222});  // late, same session: ignored
  EXPECT_EQ(state.scene().mesh.topology_version, 29u);
}

TEST(SceneState, StrokeTrailGrowsWhileCuttingAndRestartsWithTheNextStroke) {
  SceneState state;
  state.on_hand({1, {0.0f, 0.0f, 0.0f}, true, true, false});
  state.on_hand({1, {0.1f, 0.0f, 0.0f}, true, true, false});
  state.on_hand({1, {0.2f, 0.0f, 0.0f}, true, false, false});  // gate closed: trail kept, not extended
  EXPECT_EQ(state.scene().stroke.size(), 2u);
  ASSERT_TRUE(state.scene().hand);
  EXPECT_EQ(state.scene().hand->state, HandState::Idle);
  state.on_hand({2, {0.3f, 0.0f, 0.0f}, true, true, false});
  EXPECT_EQ(state.scene().stroke.size(), 1u);
}

TEST(SceneState, ALostOrNonFiniteHandHidesTheMark) {
  SceneState state;
  state.on_hand({1, {0.0f, 0.0f, 0.0f}, true, false, true});
  ASSERT_TRUE(state.scene().hand);
  EXPECT_TRUE(state.scene().hand->outside_cloth);
  state.on_hand({1, {0.0f, 0.0f, 0.0f}, false, false, false});
  EXPECT_FALSE(state.scene().hand);
  state.on_hand({1, {std::nanf(""), 0.0f, 0.0f}, true, false, false});
  EXPECT_FALSE(state.scene().hand);
}
