// Validation at the DDS boundary (idl/include/tachi/bus/input_guard.hpp): each refusal is counted
// under its reason, and a flood of made-up sources cannot grow the guard without bound.
#include "tachi/bus/input_guard.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <string>
#include <vector>

namespace tachi::bus {
namespace {

struct Counted {
  std::map<std::string, int> reasons;
  InputGuard guard{[this](std::string_view r) { ++reasons[std::string(r)]; }};
};

TEST(InputGuard, RefusesNonFiniteAndFarPositions) {
  Counted c;
  EXPECT_TRUE(c.guard.position(0.1F, -0.2F, 1.5F, 20.0F));
  EXPECT_FALSE(c.guard.position(std::numeric_limits<float>::quiet_NaN(), 0, 0, 20.0F));
  EXPECT_FALSE(c.guard.position(0, std::numeric_limits<float>::infinity(), 0, 20.0F));
  EXPECT_FALSE(c.guard.position(1e30F, 0, 0, 20.0F));
  EXPECT_EQ(c.reasons["nonfinite"], 2);
  EXPECT_EQ(c.reasons["out_of_range"], 1);
  EXPECT_EQ(c.guard.rejected(), 3u);
}

TEST(InputGuard, RefusesTimeGoingBackPerSourceButNotARestartedSource) {
  Counted c;
  EXPECT_TRUE(c.guard.time(1, 1000, 0));
  EXPECT_TRUE(c.guard.time(1, 1000, 0));  // the same frame twice is fine
  EXPECT_TRUE(c.guard.time(2, 10, 0));    // another source has its own clock
  EXPECT_FALSE(c.guard.time(1, 999, 0));
  EXPECT_EQ(c.reasons["time_backwards"], 1);
  // With a restart gap: a small step back is refused, a big one is a source that started over.
  EXPECT_FALSE(c.guard.time(1, 900, 0, 500));
  EXPECT_TRUE(c.guard.time(1, 100, 0, 500));
  EXPECT_TRUE(c.guard.time(1, 200, 0, 500));
}

TEST(InputGuard, RefusesAStrokeIdThatGoesBack) {
  Counted c;
  EXPECT_TRUE(c.guard.id(1, 3, 0));
  EXPECT_TRUE(c.guard.id(1, 3, 0));
  EXPECT_TRUE(c.guard.id(1, 4, 0));
  EXPECT_FALSE(c.guard.id(1, 2, 0));
  EXPECT_TRUE(c.guard.id(2, 1, 0));  // another session numbers its own strokes
  EXPECT_EQ(c.reasons["stale_id"], 1);
}

TEST(InputGuard, AFloodOfMadeUpSourcesStaysBounded) {
  Counted c;
  for (std::uint64_t s = 0; s < 10'000; ++s) c.guard.time(s, 1, 0);
  EXPECT_EQ(c.reasons["too_many_sources"], 10'000 - static_cast<int>(InputGuard::kMaxSources));
  EXPECT_TRUE(c.guard.time(0, 2, 0)) << "the sources it tracks keep working";
}

constexpr std::int64_t kSecond = 1'000'000'000;

TEST(InputGuard, RefusesATimeFurtherAheadThanTheSkewAndTheSourceGoesOn) {
  Counted c;
  EXPECT_TRUE(c.guard.time(1, 10 * kSecond, 100 * kSecond));
  // The sample that once poisoned a live session (boundary_test.cpp): same source, stamped INT64_MAX.
  EXPECT_FALSE(c.guard.time(1, std::numeric_limits<std::int64_t>::max(), 100 * kSecond));
  EXPECT_EQ(c.reasons["time_ahead"], 1);
  EXPECT_TRUE(c.guard.time(1, 10 * kSecond + 33'000'000, 100 * kSecond + 33'000'000)) << "the next sample is taken";
  // A source's clock may run ahead of the receiver's by the skew between two samples...
  EXPECT_TRUE(c.guard.time(1, 11 * kSecond + 900'000'000, 101 * kSecond));
  // ... and a silence lets it move on as far as the receiver's clock did.
  EXPECT_TRUE(c.guard.time(1, 20 * kSecond, 110 * kSecond));
  EXPECT_FALSE(c.guard.time(1, 24 * kSecond, 110 * kSecond));
  // A recording played faster than real time (30 Hz stamps, 1 ms apart) is never refused.
  for (std::int64_t i = 1; i <= 1000; ++i)
    EXPECT_TRUE(c.guard.time(2, i * 33'333'333, i * 1'000'000)) << i;
  EXPECT_EQ(c.guard.rejected(), 2u);
}

TEST(InputGuard, APoisonedBaselineLocksASourceOutForAtMostTheSkew) {
  Counted c;
  // The first sample a receiver sees of a source is the poisoned one: nothing to compare it with.
  EXPECT_TRUE(c.guard.time(1, std::numeric_limits<std::int64_t>::max(), 0));
  EXPECT_FALSE(c.guard.time(1, kSecond, kSecond / 2));
  EXPECT_FALSE(c.guard.time(1, 2 * kSecond, kSecond)) << "still within the skew";
  EXPECT_TRUE(c.guard.time(1, 2 * kSecond + 1, kSecond + kSecond / 2 + 1)) << "then the source starts afresh";
  EXPECT_TRUE(c.guard.time(1, 2 * kSecond + 2, kSecond + kSecond / 2 + 2));
  EXPECT_EQ(c.reasons["time_backwards"], 2);
  // One late straggler after a silence is still refused: only refusals lasting past the skew reset.
  EXPECT_FALSE(c.guard.time(1, kSecond, 100 * kSecond));
  EXPECT_TRUE(c.guard.time(1, 3 * kSecond, 100 * kSecond)) << "and its own stream goes on";
  // The same for ids: a stroke id of UINT64_MAX does not end all strokes.
  EXPECT_TRUE(c.guard.id(7, std::numeric_limits<std::uint64_t>::max(), 0));
  EXPECT_FALSE(c.guard.id(7, 3, 0));
  EXPECT_FALSE(c.guard.id(7, 3, kSecond));
  EXPECT_TRUE(c.guard.id(7, 4, kSecond + 1));
  EXPECT_TRUE(c.guard.id(7, 4, kSecond + 2));
  EXPECT_EQ(c.reasons["stale_id"], 2);
}

TEST(InputGuard, RefusesAClothStateWithANonFiniteOrFarParticle) {
  Counted c;
  std::vector<float> xyz(300, 0.5F);
  EXPECT_TRUE(c.guard.positions(xyz.data(), xyz.size(), 100.0F));
  xyz[299] = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(c.guard.positions(xyz.data(), xyz.size(), 100.0F));
  xyz[299] = -1e30F;
  EXPECT_FALSE(c.guard.positions(xyz.data(), xyz.size(), 100.0F));
  xyz[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(c.guard.positions(xyz.data(), xyz.size(), 100.0F)) << "non-finite is said first";
  EXPECT_EQ(c.reasons["nonfinite"], 2);
  EXPECT_EQ(c.reasons["out_of_range"], 1);
}

TEST(InputGuard, RefusesOversizedOrRaggedSequences) {
  Counted c;
  EXPECT_TRUE(c.guard.size(300, 300, 3));
  EXPECT_FALSE(c.guard.size(301, 1000, 3));
  EXPECT_FALSE(c.guard.size(303, 300, 3));
  EXPECT_EQ(c.reasons["oversized"], 2);
}

}  // namespace
}  // namespace tachi::bus
