// common::run_composed, the loop tachi-pipeline runs `tachi run --in-process`'s nodes with: the
// launcher's ending rule (finite nodes done -> the others get their grace, then stop), a failing node
// ending the composition with its exit code, and each thread's log lines naming their node.
#include "tachi/common/composition.hpp"

#include "tachi/common/disk_full.hpp"
#include "tachi/common/exit_codes.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <sstream>
#include <stdexcept>
#include <thread>

using tachi::common::ComposedNode;
using namespace std::chrono_literals;

namespace {

// A node that ends by itself after `spins` spins (or never, with spins < 0) and counts what it did.
struct CountingNode {
  int spins = -1;
  std::atomic<int> spun{0};
  std::atomic<bool> finished{false};
  int exit_code = tachi::common::kExitOk;

  ComposedNode as(const std::string& name, bool finite) {
    return {name, finite,
            [this] {
              std::this_thread::sleep_for(1ms);  // a node blocks briefly on its input
              return spins < 0 || ++spun <= spins;
            },
            [this] {
              finished = true;
              return exit_code;
            }};
  }
};

}  // namespace

TEST(Composition, FiniteNodesEndItAndTheOthersPassTheirLastSamplesOnDuringTheGrace) {
  CountingNode sensor, filter;
  sensor.spins = 5;
  std::atomic<int> filter_spins_when_sensor_ended{-1};
  std::vector<ComposedNode> nodes{sensor.as("sensor", true), filter.as("filter", false)};
  nodes[0].finish = [&] {
    filter_spins_when_sensor_ended = filter.spun.load();
    sensor.finished = true;
    return 0;
  };
  nodes[1].spin_once = [&] {
    std::this_thread::sleep_for(1ms);
    ++filter.spun;
    return true;  // a filter never ends by itself
  };
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 100ms), tachi::common::kExitOk);
  EXPECT_TRUE(sensor.finished);
  EXPECT_TRUE(filter.finished) << "the non-finite node was stopped, then finished (its outputs written)";
  EXPECT_GT(filter.spun.load(), filter_spins_when_sensor_ended.load()) << "it kept working during the grace";
}

TEST(Composition, ANodeThatThrowsEndsItWithTheFailureAndTheOthersFinish) {
  CountingNode filter, viewer;
  std::vector<ComposedNode> nodes{filter.as("filter", false), viewer.as("viewer", true)};
  nodes[0].spin_once = [n = 0]() mutable {
    if (++n == 3) throw std::runtime_error("the bus went away");
    return true;
  };
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 10s), tachi::common::kExitFailure)
      << "not held back by the 10 s grace: a failure ends it at once";
  EXPECT_TRUE(viewer.finished) << "the other node was stopped and wrote its outputs";
  EXPECT_FALSE(filter.finished) << "the failed node's finish is not called after it threw";
}

TEST(Composition, AFullDiskIsTheCompositionsExitCode) {
  CountingNode sim;
  std::vector<ComposedNode> nodes{sim.as("sim", true)};
  nodes[0].finish = []() -> int { throw tachi::common::DiskFull("/tmp/full/cloth.obj"); };
  sim.spins = 1;
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 0ms), tachi::common::kExitDiskFull);
}

TEST(Composition, ANodesNonZeroExitCodeIsTheCompositions) {
  CountingNode sensor, sim;
  sensor.spins = 2;
  sim.spins = 2;
  sim.exit_code = tachi::common::kExitFailure;
  std::vector<ComposedNode> nodes{sensor.as("sensor", true), sim.as("sim", true)};
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 0ms), tachi::common::kExitFailure);
  EXPECT_TRUE(sensor.finished);
}

TEST(Composition, EachThreadsLogLinesNameItsNode) {
  std::ostringstream lines;
  auto logger = std::make_shared<spdlog::logger>("composition_test", std::make_shared<spdlog::sinks::ostream_sink_mt>(lines));
  spdlog::register_logger(logger);
  const auto previous = spdlog::default_logger();
  tachi::common::log_node_names("composition_test");
  std::vector<ComposedNode> nodes{{"sim", true, [] { return false; }, [] {
                                     spdlog::info("stopped");
                                     return 0;
                                   }}};
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 0ms), 0);
  spdlog::info("outside");
  spdlog::set_default_logger(previous);
  spdlog::drop("composition_test");
  EXPECT_NE(lines.str().find("[composition_test:sim] [info] stopped"), std::string::npos) << lines.str();
  EXPECT_NE(lines.str().find("[composition_test] [info] outside"), std::string::npos) << lines.str();
}

TEST(Composition, AWindowsNodeSpinsOnTheCallingThreadAndTheOthersOnTheirOwn) {
  const auto caller = std::this_thread::get_id();
  std::atomic<bool> window_on_caller{true}, filter_on_caller{false};
  std::atomic<int> window_spins{0};
  std::vector<ComposedNode> nodes{
      {"viewer", true,
       [&] {
         window_on_caller = window_on_caller && std::this_thread::get_id() == caller;
         std::this_thread::sleep_for(1ms);
         return ++window_spins < 20;
       },
       [&] {
         window_on_caller = window_on_caller && std::this_thread::get_id() == caller;
         return 0;
       },
       true},
      {"filter", false,
       [&] {
         filter_on_caller = filter_on_caller || std::this_thread::get_id() == caller;
         std::this_thread::sleep_for(1ms);
         return true;
       },
       [] { return 0; }}};
  EXPECT_EQ(tachi::common::run_composed(std::move(nodes), 0ms), 0);
  EXPECT_EQ(window_spins.load(), 20);
  EXPECT_TRUE(window_on_caller) << "spun and finished on the thread that opened its window";
  EXPECT_FALSE(filter_on_caller);
}
