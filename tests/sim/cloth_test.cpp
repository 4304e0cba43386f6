#include "tachi/sim/cloth.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace {

using tachi::sim::Cloth;
using tachi::sim::ClothConfig;
using tachi::sim::PinMode;
using tachi::sim::SpringKind;

Cloth make(int columns, int rows, PinMode pin = PinMode::Corners) {
  ClothConfig c;
  c.columns = columns;
  c.rows = rows;
  c.pin = pin;
  return Cloth{c};
}

std::size_t count_kind(const Cloth& cloth, SpringKind k) {
  return static_cast<std::size_t>(std::count(cloth.kind.begin(), cloth.kind.end(), k));
}

TEST(Cloth, GridHasProvotSpringCountsAndTwoTrianglesPerCell) {
  const Cloth cloth = make(5, 4);
  EXPECT_EQ(cloth.particle_count(), 20U);
  EXPECT_EQ(count_kind(cloth, SpringKind::Structural), 4U * 4U + 5U * 3U);
  EXPECT_EQ(count_kind(cloth, SpringKind::Shear), 2U * 4U * 3U);
  EXPECT_EQ(count_kind(cloth, SpringKind::Bend), 3U * 4U + 5U * 2U);
  EXPECT_EQ(cloth.triangle_count(), 2U * 4U * 3U);
  EXPECT_EQ(cloth.alive_spring_count(), cloth.spring_count());
}

TEST(Cloth, HangsInZPlaneCentredWithUvIndexing) {
  const Cloth cloth = make(3, 3);
  const auto& top_left = cloth.position[cloth.index(0, 0)];
  const auto& bottom_right = cloth.position[cloth.index(2, 2)];
  EXPECT_FLOAT_EQ(top_left.x(), -0.5F);
  EXPECT_FLOAT_EQ(top_left.y(), 0.5F);
  EXPECT_FLOAT_EQ(bottom_right.x(), 0.5F);
  EXPECT_FLOAT_EQ(bottom_right.y(), -0.5F);
  EXPECT_FLOAT_EQ(cloth.position[4].z(), 0.0F);
  EXPECT_EQ(cloth.grid[cloth.index(2, 1)].u, 2);
  EXPECT_EQ(cloth.grid[cloth.index(2, 1)].v, 1);
}

TEST(Cloth, RestLengthsMatchGeometryAndStrainIsZero) {
  const Cloth cloth = make(7, 5);
  for (std::size_t k = 0; k < cloth.spring_count(); ++k) {
    const float len = (cloth.position[cloth.spring_a[k]] - cloth.position[cloth.spring_b[k]]).norm();
    EXPECT_NEAR(len, cloth.rest_length[k], 1e-5F) << "spring " << k;
  }
  EXPECT_NEAR(cloth.max_structural_strain(), 0.0F, 1e-5F);
}

TEST(Cloth, EveryTriangleEdgeIsAStructuralOrShearSpringAndFacesPlusZ) {
  const Cloth cloth = make(4, 4);
  for (const auto& tri : cloth.triangles) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = tri[static_cast<std::size_t>(e)], b = tri[static_cast<std::size_t>((e + 1) % 3)];
      bool found = false;
      for (const std::uint32_t k : cloth.springs_of(a)) {
        if ((cloth.spring_a[k] == b || cloth.spring_b[k] == b) && cloth.kind[k] != SpringKind::Bend) found = true;
      }
      EXPECT_TRUE(found) << a << "-" << b;
    }
    const Eigen::Vector3f n =
        (cloth.position[tri[1]] - cloth.position[tri[0]]).cross(cloth.position[tri[2]] - cloth.position[tri[0]]);
    EXPECT_GT(n.z(), 0.0F);
  }
}

TEST(Cloth, PinModesFixTheRightParticles) {
  const Cloth corners = make(4, 3, PinMode::Corners);
  EXPECT_EQ(std::accumulate(corners.pinned.begin(), corners.pinned.end(), 0), 2);
  EXPECT_EQ(corners.inverse_mass[0], 0.0F);
  EXPECT_EQ(corners.inverse_mass[3], 0.0F);
  EXPECT_GT(corners.inverse_mass[1], 0.0F);
  const Cloth top = make(4, 3, PinMode::TopEdge);
  EXPECT_EQ(std::accumulate(top.pinned.begin(), top.pinned.end(), 0), 4);
  const Cloth none = make(4, 3, PinMode::None);
  EXPECT_EQ(std::accumulate(none.pinned.begin(), none.pinned.end(), 0), 0);
}

TEST(Cloth, DuplicateSplitsMassAndGrowsEveryArray) {
  Cloth cloth = make(3, 3, PinMode::None);
  const float total = std::accumulate(cloth.mass.begin(), cloth.mass.end(), 0.0F);
  cloth.velocity[4] = Eigen::Vector3f{1, 2, 3};
  const std::uint32_t version = cloth.topology_version;
  const std::size_t copy = cloth.duplicate_particle(4);
  EXPECT_EQ(copy, 9U);
  EXPECT_EQ(cloth.particle_count(), 10U);
  EXPECT_EQ(cloth.velocity.size(), 10U);
  EXPECT_EQ(cloth.grid[copy], cloth.grid[4]);
  EXPECT_EQ(cloth.velocity[copy], cloth.velocity[4]);
  EXPECT_FLOAT_EQ(cloth.mass[copy], cloth.mass[4]);
  EXPECT_FLOAT_EQ(cloth.inverse_mass[copy], 1.0F / cloth.mass[copy]);
  EXPECT_NEAR(std::accumulate(cloth.mass.begin(), cloth.mass.end(), 0.0F), total, 1e-6F);
  EXPECT_TRUE(cloth.springs_of(copy).empty());
  EXPECT_NE(cloth.topology_version, version);
}

TEST(Cloth, RewireAndRemoveKeepIncidenceConsistent) {
  Cloth cloth = make(3, 3, PinMode::None);
  const std::size_t copy = cloth.duplicate_particle(4);
  const std::uint32_t k = cloth.springs_of(4)[0];
  const std::size_t before = cloth.springs_of(4).size();
  ASSERT_TRUE(cloth.rewire_spring(k, 4, static_cast<std::uint32_t>(copy)));
  EXPECT_EQ(cloth.springs_of(4).size(), before - 1);
  ASSERT_EQ(cloth.springs_of(copy).size(), 1U);
  EXPECT_EQ(cloth.springs_of(copy)[0], k);
  EXPECT_TRUE(cloth.spring_a[k] == copy || cloth.spring_b[k] == copy);
  EXPECT_FALSE(cloth.rewire_spring(k, 4, 0));  // 4 is no longer an endpoint
  cloth.remove_spring(k);
  cloth.remove_spring(k);
  EXPECT_EQ(cloth.alive[k], 0);
  EXPECT_TRUE(cloth.springs_of(copy).empty());

  const std::uint32_t t = cloth.triangles_of(4)[0];
  ASSERT_TRUE(cloth.rewire_triangle(t, 4, static_cast<std::uint32_t>(copy)));
  EXPECT_EQ(cloth.triangles_of(copy).size(), 1U);
  cloth.remove_triangle(t);
  EXPECT_TRUE(cloth.triangles_of(copy).empty());
  EXPECT_EQ(cloth.alive_triangle_count(), cloth.triangle_count() - 1);
}

TEST(Cloth, AddSpringTakesRestLengthFromGrid) {
  Cloth cloth = make(5, 5, PinMode::None);
  const std::uint32_t k = cloth.add_spring(cloth.index(0, 0), cloth.index(2, 2), SpringKind::Shear);
  EXPECT_NEAR(cloth.rest_length[k], std::sqrt(2.0F) * 0.5F, 1e-6F);
  EXPECT_TRUE(cloth.alive[k]);
}

TEST(SmallIndexList, SpillsToHeapWithoutLosingItems) {
  tachi::sim::SmallIndexList<2> list;
  for (std::uint32_t i = 0; i < 5; ++i) list.push_back(i);
  EXPECT_EQ(list.size(), 5U);
  EXPECT_TRUE(list.erase(1));
  EXPECT_FALSE(list.erase(1));
  EXPECT_EQ(list.size(), 4U);
  EXPECT_TRUE(list.contains(4));
}

}  // namespace
