// TopologyAssembler: keyframes + deltas -> the current topology, as every reader builds it.
#include "tachi/bus/topology_assembler.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <vector>

namespace {

using Triangle = std::array<std::uint32_t, 3>;

/// Owns the arrays a message points into.
struct Keyframe {
  std::vector<std::uint32_t> triangles;
  std::vector<tachi_msg_GridCoord> grid;
  std::vector<std::uint8_t> pinned;
  tachi_msg_ClothTopology msg{};
  Keyframe(std::uint64_t session, std::uint32_t version, std::vector<Triangle> tris, std::size_t particles) {
    for (const Triangle& t : tris) triangles.insert(triangles.end(), t.begin(), t.end());
    grid.resize(particles);
    pinned.assign(particles, 0);
    msg.session_id = session;
    msg.version = version;
    msg.triangles = {static_cast<std::uint32_t>(triangles.size()), static_cast<std::uint32_t>(triangles.size()),
                     triangles.data(), false};
    msg.particle_grid = {static_cast<std::uint32_t>(grid.size()), static_cast<std::uint32_t>(grid.size()), grid.data(), false};
    msg.pinned = {static_cast<std::uint32_t>(pinned.size()), static_cast<std::uint32_t>(pinned.size()),
                  reinterpret_cast<bool*>(pinned.data()), false};
  }
};

struct Delta {
  std::vector<tachi_msg_GridCoord> grid;
  std::vector<std::uint8_t> pinned;
  std::vector<std::uint32_t> removed;
  std::vector<std::uint32_t> added;
  tachi_msg_ClothTopologyDelta msg{};
  Delta(std::uint64_t session, std::uint32_t base, std::uint32_t version, std::size_t new_particles,
        std::vector<Triangle> gone, std::vector<Triangle> made) {
    grid.resize(new_particles);
    pinned.assign(new_particles, 0);
    for (const Triangle& t : gone) removed.insert(removed.end(), t.begin(), t.end());
    for (const Triangle& t : made) added.insert(added.end(), t.begin(), t.end());
    msg.session_id = session;
    msg.base_version = base;
    msg.version = version;
    msg.new_particle_grid = {static_cast<std::uint32_t>(grid.size()), static_cast<std::uint32_t>(grid.size()), grid.data(), false};
    msg.new_particle_pinned = {static_cast<std::uint32_t>(pinned.size()), static_cast<std::uint32_t>(pinned.size()),
                               reinterpret_cast<bool*>(pinned.data()), false};
    msg.removed_triangles = {static_cast<std::uint32_t>(removed.size()), static_cast<std::uint32_t>(removed.size()),
                             removed.data(), false};
    msg.added_triangles = {static_cast<std::uint32_t>(added.size()), static_cast<std::uint32_t>(added.size()), added.data(), false};
  }
};

std::set<Triangle> triangles(const tachi::bus::TopologyAssembler& a) {
  return {a.triangles().begin(), a.triangles().end()};
}

TEST(TopologyAssembler, AppliesDeltasInOrderOnTheKeyframe) {
  tachi::bus::TopologyAssembler a;
  Keyframe k{7, 3, {{0, 1, 2}, {1, 3, 2}}, 4};
  EXPECT_TRUE(a.on_keyframe(k.msg));
  Delta d1{7, 3, 4, 1, {{1, 3, 2}}, {{1, 4, 2}, {4, 3, 2}}};
  EXPECT_TRUE(a.on_delta(d1.msg));
  EXPECT_EQ(a.version(), 4u);
  EXPECT_EQ(a.particle_count(), 5u);
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{0, 1, 2}, {1, 4, 2}, {4, 3, 2}}));
  EXPECT_FALSE(a.on_delta(d1.msg)) << "an old delta again changes nothing";
  EXPECT_EQ(triangles(a).size(), 3u);
}

TEST(TopologyAssembler, AMissedDeltaWaitsForTheGapOrTheNextKeyframe) {
  tachi::bus::TopologyAssembler a;
  Keyframe k{7, 3, {{0, 1, 2}}, 3};
  a.on_keyframe(k.msg);
  Delta d1{7, 3, 4, 1, {}, {{1, 3, 2}}};
  Delta d2{7, 4, 5, 0, {{0, 1, 2}}, {}};
  EXPECT_FALSE(a.on_delta(d2.msg)) << "the delta before it is missing";
  EXPECT_TRUE(a.waiting_for_keyframe());
  EXPECT_EQ(a.version(), 3u);
  EXPECT_TRUE(a.on_delta(d1.msg)) << "the gap is filled: both apply";
  EXPECT_EQ(a.version(), 5u);
  EXPECT_FALSE(a.waiting_for_keyframe());
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{1, 3, 2}}));

  // A delta lost for good: the next keyframe catches the reader up, and the later deltas apply.
  Delta d4{7, 6, 7, 0, {}, {{0, 1, 2}}};
  EXPECT_FALSE(a.on_delta(d4.msg));
  Keyframe k6{7, 6, {{1, 3, 2}, {3, 0, 2}}, 4};
  EXPECT_TRUE(a.on_keyframe(k6.msg));
  EXPECT_EQ(a.version(), 7u);
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{1, 3, 2}, {3, 0, 2}, {0, 1, 2}}));
}

TEST(TopologyAssembler, AnOlderKeyframeIsIgnoredAndANewSessionStartsAfresh) {
  tachi::bus::TopologyAssembler a;
  Keyframe k{7, 5, {{0, 1, 2}}, 3};
  a.on_keyframe(k.msg);
  Keyframe older{7, 4, {{2, 1, 0}}, 3};
  EXPECT_FALSE(a.on_keyframe(older.msg));
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{0, 1, 2}}));
  Keyframe restarted{8, 0, {{0, 2, 1}}, 3};
  EXPECT_TRUE(a.on_keyframe(restarted.msg)) << "a restarted simulator counts versions afresh";
  EXPECT_EQ(a.session_id(), 8u);
  Delta stale{7, 5, 6, 0, {}, {{1, 2, 0}}};
  EXPECT_FALSE(a.on_delta(stale.msg));
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{0, 2, 1}}));
}

TEST(TopologyAssembler, DeltasBeforeTheFirstKeyframeApplyOnceItArrives) {
  tachi::bus::TopologyAssembler a;
  Delta d{7, 2, 3, 0, {{0, 1, 2}}, {{0, 1, 3}}};
  EXPECT_FALSE(a.on_delta(d.msg));
  EXPECT_FALSE(a.has_topology());
  Keyframe k{7, 2, {{0, 1, 2}}, 4};
  EXPECT_TRUE(a.on_keyframe(k.msg));
  EXPECT_EQ(a.version(), 3u);
  EXPECT_EQ(triangles(a), (std::set<Triangle>{{0, 1, 3}}));
}

}  // namespace
