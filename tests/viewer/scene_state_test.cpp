#include "tachi/viewer/scene_state.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace tachi::viewer;

namespace {
TopologyUpdate triangles(std::uint32_t version, std::vector<std::array<std::uint32_t, 3>> list) {
  TopologyUpdate t;
  t.version = version;
  t.triangles = std::move(list);
  return t;
}
TopologyUpdate in_session(TopologyUpdate t, std::uint64_t session) {
  t.session_id = session;
  return t;
}
HandUpdate hand(std::uint32_t stroke, Eigen::Vector3f at, bool tracked, bool cutting, bool outside) {
  HandUpdate h;
  h.stroke_id = stroke;
  h.position_m = at;
  h.tracked = tracked;
  h.cutting = cutting;
  h.outside_cloth = outside;
  return h;
}
}  // namespace

TEST(SceneState, StatusSaysWhatIsMissing) {
  SceneState state;
  EXPECT_NE(state.scene().status.find("waiting for the cloth topology"), std::string::npos);
  state.on_topology(triangles(1, {{0, 1, 2}}));
  EXPECT_NE(state.scene().status.find("waiting for cloth positions"), std::string::npos);
  state.on_state({7, 1, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}});
  EXPECT_TRUE(state.has_cloth());
  EXPECT_NE(state.scene().status.find("frame 7"), std::string::npos);
}

TEST(SceneState, AnOlderTopologyArrivingLateIsIgnored) {
  SceneState state;
  state.on_topology(triangles(3, {{0, 1, 2}, {1, 2, 3}}));
  state.on_topology(triangles(2, {{0, 1, 2}}));
  EXPECT_EQ(state.scene().mesh.topology_version, 3u);
  EXPECT_EQ(state.scene().mesh.triangles.size(), 2u);
}

// A restarted simulator counts versions from 1 again; its new session is followed.
TEST(SceneState, ARestartedSimulatorsNewSessionIsFollowedWhateverItsVersion) {
  SceneState state;
  state.on_topology(in_session(triangles(30, {{0, 1, 2}, {1, 2, 3}}), 111));
  state.on_topology(in_session(triangles(1, {{0, 1, 2}}), 222));
  // Taken once the new run's first state confirms it (a stray publisher of another session
  // must not take the view).
  StateUpdate first_state;
  first_state.topology_version = 1;
  first_state.session_id = 222;
  first_state.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  state.on_state(first_state);
  EXPECT_EQ(state.scene().mesh.topology_version, 1u);
  EXPECT_EQ(state.scene().mesh.triangles.size(), 1u);
  state.on_topology(in_session(triangles(29, {{0, 1, 2}, {1, 2, 3}}), 222));
  state.on_topology(in_session(triangles(5, {{0, 1, 2}}), 222));  // late, same session: ignored
  EXPECT_EQ(state.scene().mesh.topology_version, 29u);
}

TEST(SceneState, StrokeTrailGrowsWhileCuttingAndRestartsWithTheNextStroke) {
  SceneState state;
  state.on_hand(hand(1, {0.0f, 0.0f, 0.0f}, true, true, false));
  state.on_hand(hand(1, {0.1f, 0.0f, 0.0f}, true, true, false));
  state.on_hand(hand(1, {0.2f, 0.0f, 0.0f}, true, false, false));  // gate closed: trail kept, not extended
  EXPECT_EQ(state.scene().stroke.size(), 2u);
  ASSERT_TRUE(state.scene().hand);
  EXPECT_EQ(state.scene().hand->state, HandState::Idle);
  state.on_hand(hand(2, {0.3f, 0.0f, 0.0f}, true, true, false));
  EXPECT_EQ(state.scene().stroke.size(), 1u);
}

TEST(SceneState, ALostOrNonFiniteHandHidesTheMark) {
  SceneState state;
  state.on_hand(hand(1, {0.0f, 0.0f, 0.0f}, true, false, true));
  ASSERT_TRUE(state.scene().hand);
  EXPECT_TRUE(state.scene().hand->outside_cloth);
  state.on_hand(hand(1, {0.0f, 0.0f, 0.0f}, false, false, false));
  EXPECT_FALSE(state.scene().hand);
  state.on_hand(hand(1, {std::nanf(""), 0.0f, 0.0f}, true, false, false));
  EXPECT_FALSE(state.scene().hand);
}

namespace {
// A 3x3-particle cloth of version `version`, session `session`: 8 triangles, grid coordinates packed.
TopologyUpdate topology(std::uint32_t version, std::uint64_t session = 7) {
  TopologyUpdate t;
  t.version = version;
  t.session_id = session;
  t.columns = 3;
  t.rows = 3;
  for (std::uint32_t v = 0; v < 3; ++v)
    for (std::uint32_t u = 0; u < 3; ++u) t.grid.push_back(u | v << 16);
  for (std::uint32_t v = 0; v < 2; ++v)
    for (std::uint32_t u = 0; u < 2; ++u) {
      const std::uint32_t i = v * 3 + u;
      t.triangles.push_back({i, i + 1, i + 3});
      t.triangles.push_back({i + 1, i + 4, i + 3});
    }
  return t;
}

StateUpdate state(std::uint32_t version, float shift = 0.0f, std::uint64_t session = 7, std::size_t particles = 9) {
  StateUpdate s;
  s.topology_version = version;
  s.session_id = session;
  for (std::size_t i = 0; i < particles; ++i)
    s.positions.emplace_back(static_cast<float>(i % 3) * 0.1f, -static_cast<float>(i / 3) * 0.1f + shift, 0.0f);
  return s;
}
}  // namespace

TEST(SceneState, BadInputsAreRejectedCountedAndTheRealClothStaysShown) {
  SceneState s;
  ASSERT_FALSE(s.on_topology(topology(1)));
  ASSERT_FALSE(s.on_state(state(1)));
  const auto shown = s.scene().mesh;

  // A version that jumps implausibly, a triangle index out of range, arrays that do not fit.
  EXPECT_EQ(s.on_topology(topology(1000)), Rejection::VersionJump);
  auto out_of_range = topology(2);
  out_of_range.triangles.push_back({0, 1, 99});
  EXPECT_EQ(s.on_topology(out_of_range), Rejection::OutOfRange);
  auto wrong_pins = topology(2);
  wrong_pins.pinned = {1, 0};
  EXPECT_EQ(s.on_topology(wrong_pins), Rejection::Malformed);
  auto malformed = topology(2);
  malformed.malformed = true;
  EXPECT_EQ(s.on_topology(malformed), Rejection::Malformed);
  EXPECT_EQ(s.on_topology(TopologyUpdate{}), Rejection::Malformed) << "no triangles at all";

  // NaN positions, absurd coordinates, the wrong number of positions.
  auto nan = state(1);
  nan.positions[4].y() = std::nanf("");
  EXPECT_EQ(s.on_state(nan), Rejection::NonFinite);
  auto far = state(1);
  far.positions[4].x() = 1e30f;
  EXPECT_EQ(s.on_state(far), Rejection::OutOfRange);
  EXPECT_EQ(s.on_state(state(1, 0.0f, 7, 5)), Rejection::Malformed);
  EXPECT_EQ(s.on_state(state(1, 0.0f, 7, 12)), Rejection::Malformed) << "same version, other particle count";

  EXPECT_EQ(s.rejected(), 9u);
  EXPECT_EQ(s.rejected_by_reason().at("version_jump"), 1u);
  EXPECT_EQ(s.rejected_by_reason().at("nonfinite"), 1u);
  EXPECT_EQ(s.scene().mesh.topology_version, 1u);
  EXPECT_EQ(s.scene().mesh.triangles, shown.triangles);
  EXPECT_EQ(s.scene().mesh.positions, shown.positions);

  // The real cloth goes on: the next plausible versions are taken.
  EXPECT_FALSE(s.on_topology(topology(2)));
  EXPECT_FALSE(s.on_state(state(2, -0.05f)));
  EXPECT_EQ(s.scene().mesh.topology_version, 2u);
  EXPECT_FLOAT_EQ(s.scene().mesh.positions[0].y(), -0.05f);
}

TEST(SceneState, AJumpConfirmedByTheClothStatesIsTaken) {
  SceneState s;
  s.on_topology(topology(1));
  s.on_state(state(1));
  EXPECT_EQ(s.on_topology(topology(900)), Rejection::VersionJump);
  EXPECT_EQ(s.scene().mesh.topology_version, 1u);
  EXPECT_FALSE(s.on_state(state(900)));
  EXPECT_EQ(s.scene().mesh.topology_version, 900u);
}

TEST(SceneState, AStrayPublisherOfAnotherSessionDoesNotTakeTheView) {
  SceneState s;
  s.on_topology(topology(1, 7));
  s.on_state(state(1, 0.0f, 7));
  EXPECT_FALSE(s.on_topology(topology(1000, 99)));
  EXPECT_FALSE(s.on_state(state(1, 0.1f, 7)));
  EXPECT_EQ(s.scene().mesh.topology_version, 1u);
  EXPECT_EQ(s.session_id(), 7u);
}

TEST(SceneState, AnImplausibleFirstTopologyGivesWayToTheOneTheStatesUse) {
  SceneState s;
  EXPECT_FALSE(s.on_topology(topology(1000)));  // taken: nothing else to show yet
  EXPECT_FALSE(s.on_topology(topology(1)));     // older: set aside
  EXPECT_EQ(s.scene().mesh.topology_version, 1000u);
  EXPECT_FALSE(s.on_state(state(1)));
  EXPECT_EQ(s.scene().mesh.topology_version, 1u);
}

TEST(SceneState, ASimulatorRestartIsFollowed) {
  SceneState s;
  s.on_topology(topology(40, 7));
  s.on_state(state(40, 0.0f, 7));
  s.on_cut({1, 40, {1u | 1u << 16}, 2, 1, 7, 1}, 0.0);
  ASSERT_EQ(s.pieces(), 2u);
  EXPECT_FALSE(s.on_topology(topology(0, 8)));  // new session, version back to 0
  EXPECT_EQ(s.scene().mesh.topology_version, 40u) << "not before a state of the new session confirms it";
  EXPECT_FALSE(s.on_state(state(40, 0.1f, 7)));
  EXPECT_FALSE(s.on_state(state(0, 0.2f, 8)));
  EXPECT_EQ(s.scene().mesh.topology_version, 0u);
  EXPECT_FLOAT_EQ(s.scene().mesh.positions[0].y(), 0.2f);
  EXPECT_FALSE(s.pieces()) << "the previous run's pieces are not this run's";
  EXPECT_EQ(s.on_state(state(40, 0.0f, 7)), Rejection::StaleSession) << "a late state of the old run";
}

TEST(SceneState, ACutFlashesAlongItsLineAndFades) {
  SceneState s;
  s.on_topology(topology(1));
  s.on_state(state(1));
  EXPECT_FALSE(s.on_cut({1, 1, {0u | 1u << 16, 1u | 1u << 16, 2u | 1u << 16}, 2, 1, 7, 1}, 10.0));
  EXPECT_EQ(s.scene().cut_particles, (std::vector<std::uint32_t>{3, 4, 5}));
  EXPECT_FLOAT_EQ(s.scene().flash, 1.0f);
  EXPECT_EQ(s.fallen_pieces(), 1u);
  s.advance(10.0 + SceneState::kFlashSeconds / 2);
  EXPECT_NEAR(s.scene().flash, 0.5f, 1e-3f);
  s.advance(10.0 + SceneState::kFlashSeconds);
  EXPECT_EQ(s.scene().flash, 0.0f);
}

TEST(SceneState, AnotherSourceIdleSamplesDoNotTakeTheMarkFromACuttingOne) {
  SceneState s;
  HandUpdate mouse = hand(1, {0.1f, 0.0f, 0.0f}, true, true, false);
  mouse.sensor_id = 1000;
  mouse.gate = "cutting (mouse)";
  HandUpdate camera = hand(3, {-0.3f, 0.2f, 0.0f}, true, false, false);
  camera.sensor_id = 1;
  camera.gate = "idle (threshold)";
  s.on_hand(mouse);
  s.on_hand(camera);
  ASSERT_TRUE(s.scene().hand);
  EXPECT_EQ(s.scene().hand->state, HandState::Cutting);
  EXPECT_EQ(s.gate(), "cutting (mouse)");
  mouse.cutting = false;
  s.on_hand(mouse);
  s.on_hand(camera);
  EXPECT_EQ(s.gate(), "idle (threshold)");
  EXPECT_FLOAT_EQ(s.scene().hand->position_m.x(), -0.3f);
}

TEST(SceneState, AnExactCutWithoutAGridLineFlashesWhatItSplit) {
  SceneState s;
  s.on_topology(topology(1));
  s.on_state(state(1));
  // Version 2 splits particles 3 and 4 (new particles 9 and 10 at the same grid cells).
  auto split = topology(2);
  split.grid.push_back(0u | 1u << 16);
  split.grid.push_back(1u | 1u << 16);
  split.duplicated_from = {3, 4};
  EXPECT_FALSE(s.on_topology(split));
  EXPECT_FALSE(s.on_cut({1, 2, {}, 2, 1, 7, 1}, 0.0));
  auto flashed = s.scene().cut_particles;
  std::sort(flashed.begin(), flashed.end());
  EXPECT_EQ(flashed, (std::vector<std::uint32_t>{3, 4, 9, 10}));
  EXPECT_FLOAT_EQ(s.scene().flash, 1.0f);
  EXPECT_FALSE(s.on_cut({2, 2, {}, 2, 1, 7, 1}, 1.0));
  EXPECT_TRUE(s.scene().cut_particles.empty()) << "each cut flashes its own splits";
}

// A cut's new topology (more particles) can overtake cloth states of the topology before it that are
// still queued: those are outdated, not malformed. They are not shown and not counted as rejected (a
// clean run showed "rejected 2 (malformed)").
TEST(SceneState, AStateOfTheTopologyBeforeACutIsOutdatedNotRejected) {
  SceneState s;
  ASSERT_FALSE(s.on_topology(topology(1)));
  ASSERT_FALSE(s.on_state(state(1)));
  auto cut = topology(2);
  cut.grid.push_back(1 | 1u << 16);  // the cut split particle 4: particle 9 is its copy
  cut.duplicated_from = {4};
  cut.triangles.back() = {5, 9, 7};
  ASSERT_FALSE(s.on_topology(cut));
  EXPECT_FALSE(s.on_state(state(1, -0.05f))) << "queued before the cut";
  EXPECT_EQ(s.rejected(), 0u);
  EXPECT_FLOAT_EQ(s.scene().mesh.positions[0].y(), 0.0f) << "the outdated state is not shown";
  EXPECT_FALSE(s.on_state(state(2, -0.07f, 7, 10)));
  EXPECT_FLOAT_EQ(s.scene().mesh.positions[0].y(), -0.07f);
  EXPECT_EQ(s.outdated_states(), 1u);
}
