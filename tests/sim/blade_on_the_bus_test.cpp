// The blade crosses the bus as tachi.idl's Blade (the value of tachi-sim's heartbeat metric "blade"): every
// simulator blade keeps its --blade name through it, so the viewer names it without linking tachi_sim.
#include "bus_adapter.hpp"
#include "tachi/bus/blade.hpp"
#include "tachi/sim/blade.hpp"

#include <gtest/gtest.h>

#include <cmath>

using tachi::sim::Blade;

TEST(BladeOnTheBus, EveryBladeKeepsItsNameThroughTheIdlEnum) {
  for (const Blade blade : {Blade::Razor, Blade::Scalpel, Blade::Utility, Blade::Kitchen, Blade::Hunting, Blade::Worn}) {
    const double metric = static_cast<double>(tachi::sim::to_msg(blade));  // what the heartbeat carries
    const auto name = tachi::bus::blade_name(metric);
    ASSERT_TRUE(name) << tachi::sim::to_string(blade);
    EXPECT_EQ(*name, tachi::sim::to_string(blade));
    EXPECT_EQ(tachi::sim::parse_blade(*name), blade) << "the name is also the --blade flag's";
  }
}

TEST(BladeOnTheBus, AValueThatIsNoBladeHasNoName) {
  EXPECT_FALSE(tachi::bus::blade_name(-1.0));
  EXPECT_FALSE(tachi::bus::blade_name(6.0));
  EXPECT_FALSE(tachi::bus::blade_name(1.5));
  EXPECT_FALSE(tachi::bus::blade_name(std::nan("")));
}
