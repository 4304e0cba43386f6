// Validation at the DDS boundary (idl/include/tachi/bus/input_guard.hpp): each refusal is counted
// under its reason, and a flood of made-up sources cannot grow the guard without bound.
#include "tachi/bus/input_guard.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <string>

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
  EXPECT_TRUE(c.guard.time(1, 1000));
  EXPECT_TRUE(c.guard.time(1, 1000));  // the same frame twice is fine
  EXPECT_TRUE(c.guard.time(2, 10));    // another source has its own clock
  EXPECT_FALSE(c.guard.time(1, 999));
  EXPECT_EQ(c.reasons["time_backwards"], 1);
  // With a restart gap: a small step back is refused, a big one is a source that started over.
  EXPECT_FALSE(c.guard.time(1, 900, 500));
  EXPECT_TRUE(c.guard.time(1, 100, 500));
  EXPECT_TRUE(c.guard.time(1, 200, 500));
}

TEST(InputGuard, RefusesAStrokeIdThatGoesBack) {
  Counted c;
  EXPECT_TRUE(c.guard.id(1, 3));
  EXPECT_TRUE(c.guard.id(1, 3));
  EXPECT_TRUE(c.guard.id(1, 4));
  EXPECT_FALSE(c.guard.id(1, 2));
  EXPECT_TRUE(c.guard.id(2, 1));  // another session numbers its own strokes
  EXPECT_EQ(c.reasons["stale_id"], 1);
}

TEST(InputGuard, AFloodOfMadeUpSourcesStaysBounded) {
  Counted c;
  for (std::uint64_t s = 0; s < 10'000; ++s) c.guard.time(s, 1);
  EXPECT_EQ(c.reasons["too_many_sources"], 10'000 - static_cast<int>(InputGuard::kMaxSources));
  EXPECT_TRUE(c.guard.time(0, 2)) << "the sources it tracks keep working";
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
