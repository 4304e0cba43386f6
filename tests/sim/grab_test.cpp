#include "tachi/sim/grab.hpp"
#include "tachi/sim/solver.hpp"

#include <gtest/gtest.h>

namespace {

using namespace tachi::sim;

Cloth hanging(int n) {
  ClothConfig c;
  c.columns = n;
  c.rows = n;
  c.pin = PinMode::Corners;
  return Cloth{c};
}

TEST(Grab, NearestParticleIsTheClosestLiveOne) {
  Cloth cloth = hanging(5);
  EXPECT_EQ(nearest_particle(cloth, Eigen::Vector3f{0.26F, -0.24F, 0.1F}), cloth.index(3, 3));
  EXPECT_FALSE(nearest_particle(cloth, Eigen::Vector3f{0.0F, 0.0F, 2.0F}, 0.5F).has_value());
  // A particle left without springs or triangles by a cut is never picked.
  const std::uint32_t i = cloth.index(2, 2);
  for (const std::uint32_t k : std::vector<std::uint32_t>(cloth.springs_of(i).begin(), cloth.springs_of(i).end())) {
    cloth.remove_spring(k);
  }
  for (const std::uint32_t t : std::vector<std::uint32_t>(cloth.triangles_of(i).begin(), cloth.triangles_of(i).end())) {
    cloth.remove_triangle(t);
  }
  EXPECT_NE(nearest_particle(cloth, cloth.position[i]), i);
}

TEST(Grab, GrabbedParticleFollowsTheHandAndIsReleased) {
  Cloth cloth = hanging(24);
  Solver solver;
  for (int s = 0; s < 60; ++s) solver.step(cloth);
  Grab grab;
  const Eigen::Vector3f start = cloth.position[cloth.index(12, 23)];
  const auto held = grab.grab(cloth, start + Eigen::Vector3f{0.0F, 0.0F, 0.01F}, 0.1F);
  ASSERT_TRUE(held.has_value());
  EXPECT_EQ(*held, cloth.index(12, 23));
  const float dt = solver.params().dt;
  Eigen::Vector3f hand = start;
  for (int s = 0; s < 60; ++s) {
    hand += Eigen::Vector3f{0.0F, 0.004F, 0.006F};  // lift the bottom edge towards the viewer
    grab.move(cloth, hand, dt);
    solver.step(cloth);
    ASSERT_EQ(cloth.position[*held], hand) << "step " << s;
  }
  // Its neighbours came along.
  EXPECT_GT(cloth.position[cloth.index(12, 22)].z(), 0.25F);
  EXPECT_LE(cloth.max_structural_strain(), 0.10F);

  grab.release(cloth);
  EXPECT_FALSE(grab.held().has_value());
  EXPECT_GT(cloth.inverse_mass[*held], 0.0F);
  const Eigen::Vector3f at_release = cloth.position[*held];
  for (int s = 0; s < 30; ++s) solver.step(cloth);
  EXPECT_LT(cloth.position[*held].y(), at_release.y() - 0.05F);  // given back to gravity
}

TEST(Grab, OneHandHoldsOneParticleAndPinsStayPinned) {
  Cloth cloth = hanging(8);
  Grab grab;
  const auto first = grab.grab(cloth, cloth.position[0]);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(*first, 0U);
  EXPECT_EQ(grab.grab(cloth, cloth.position[20]), first);  // still holding the first
  grab.release(cloth);
  EXPECT_EQ(cloth.inverse_mass[0], 0.0F);  // a pinned particle stays pinned after release
  grab.release(cloth);                     // releasing an empty hand is harmless
  grab.move(cloth, Eigen::Vector3f::Zero(), 0.1F);
  EXPECT_FALSE(grab.grab(cloth, Eigen::Vector3f{std::nanf(""), 0.0F, 0.0F}).has_value());
}

}  // namespace
