#include "tachi/launcher/config.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace tachi::launcher;
using nlohmann::json;

namespace {
const ChildSpec& child(const std::vector<ChildSpec>& children, const std::string& node) {
  const auto it = std::find_if(children.begin(), children.end(), [&](const auto& c) { return c.node == node; });
  if (it == children.end()) throw std::runtime_error("no " + node);
  return *it;
}
bool has_pair(const std::vector<std::string>& args, const std::string& flag, const std::string& value) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == flag && args[i + 1] == value) return true;
  return false;
}
}  // namespace

TEST(RunConfig, DefaultsStartTheFourNodesConsumersFirstOnOneDomain) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["domain"] = 7;
  const auto children = plan(from_json(j));
  std::vector<std::string> order;
  for (const auto& c : children) order.push_back(c.node);
  EXPECT_EQ(order, (std::vector<std::string>{"sim", "viewer", "filter", "sensor"}));
  for (const auto& c : children) EXPECT_TRUE(has_pair(c.args, "--domain", "7")) << c.program;
  EXPECT_TRUE(has_pair(child(children, "sensor").args, "--recording", "/rec"));
  EXPECT_TRUE(has_pair(child(children, "sim").args, "--pin", "top-edge"));
  EXPECT_TRUE(has_pair(child(children, "sim").args, "--export", "out/run/sim"));
  EXPECT_TRUE(has_pair(child(children, "sim").args, "--journal", "out/run/sim.journal"));
  EXPECT_TRUE(child(children, "sensor").finite);
  EXPECT_FALSE(child(children, "filter").finite);
  // Without a display the viewer runs headless.
  const auto& v = child(children, "viewer").args;
  EXPECT_NE(std::find(v.begin(), v.end(), "--headless"), v.end());
}

TEST(RunConfig, NodeOptionsPassThroughAsFlags) {
  json j = default_config_json(true);
  merge_into(j, json::parse(R"({"sim": {"material": "denim", "substeps": 4, "verbose": true, "quiet": false,
                                        "sphere": [[0, 0, 0.1, 0.05], [0.2, 0, 0.1, 0.05]]}})"));
  const auto args = pass_through_args(from_json(j).node_options["sim"]);
  EXPECT_TRUE(has_pair(args, "--material", "denim"));
  EXPECT_TRUE(has_pair(args, "--substeps", "4"));
  EXPECT_NE(std::find(args.begin(), args.end(), "--verbose"), args.end());
  EXPECT_EQ(std::find(args.begin(), args.end(), "--quiet"), args.end());
  EXPECT_EQ(std::count(args.begin(), args.end(), "--sphere"), 2);
  EXPECT_TRUE(has_pair(args, "--pin", "top-edge")) << "the default stays unless overridden";
}

TEST(RunConfig, TheSimulatorMapsARecordedObjectWithTheFiltersWorkspace) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  const auto plain = child(plan(from_json(j)), "sim").args;
  EXPECT_EQ(std::count(plain.begin(), plain.end(), "--workspace-config"), 0) << "no filter config: both keep the default mapping";
  merge_into(j, parse_set("filter.config=/cfg/filter.json"));
  EXPECT_TRUE(has_pair(child(plan(from_json(j)), "sim").args, "--workspace-config", "/cfg/filter.json"));
  merge_into(j, parse_set("sim.workspace-config=/cfg/other.json"));
  const auto sim = child(plan(from_json(j)), "sim").args;
  EXPECT_EQ(std::count(sim.begin(), sim.end(), "--workspace-config"), 1) << "sim.workspace-config wins, given once";
  EXPECT_TRUE(has_pair(sim, "--workspace-config", "/cfg/other.json"));
}

TEST(RunConfig, SetAssignsOneNodeFlagWithJsonValues) {
  EXPECT_EQ(parse_set("sim.material=denim"), json::parse(R"({"sim": {"material": "denim"}})"));
  EXPECT_EQ(parse_set("viewer.mouse=true"), json::parse(R"({"viewer": {"mouse": true}})"));
  EXPECT_EQ(parse_set("sim.substeps=4"), json::parse(R"({"sim": {"substeps": 4}})"));
  EXPECT_THROW((void)parse_set("material=denim"), std::invalid_argument);
  EXPECT_THROW((void)parse_set("sim.material"), std::invalid_argument);
}

TEST(RunConfig, NodesSubsetStartsOnlyThose) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["nodes"] = "sensor,filter";
  const auto children = plan(from_json(j));
  ASSERT_EQ(children.size(), 2u);
  EXPECT_EQ(children[0].node, "filter");
  EXPECT_EQ(children[1].node, "sensor");
}

TEST(RunConfig, VoiceSourceAddsTheVoiceNode) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["gate"] = "voice";
  j["voice_wav"] = "/a.wav";
  const auto children = plan(from_json(j));
  EXPECT_TRUE(has_pair(child(children, "voice").args, "--wav", "/a.wav"));
  EXPECT_TRUE(has_pair(child(children, "filter").args, "--gate", "voice"));
}

TEST(RunConfig, BadValuesNameTheirKey) {
  const auto message = [](json j) {
    try {
      (void)from_json(j);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  json base = default_config_json(false);
  json j = base;
  j["grid"] = 1;
  EXPECT_NE(message(j).find("\"grid\""), std::string::npos) << message(j);
  j = base;
  j["gate"] = "clap";
  EXPECT_NE(message(j).find("\"gate\""), std::string::npos);
  j = base;
  j["gate"] = "voice";  // no voice source
  EXPECT_NE(message(j).find("\"gate\""), std::string::npos);
  j = base;
  j["nodes"] = "sensor,toaster";
  EXPECT_NE(message(j).find("toaster"), std::string::npos);
  j = base;
  j["colour"] = "red";
  EXPECT_NE(message(j).find("\"colour\""), std::string::npos);
  j = base;
  j["grid"] = "big";
  EXPECT_NE(message(j).find("wrong type"), std::string::npos);
  j = base;
  j["sim"] = json{{"--grid", 3}};
  EXPECT_NE(message(j).find("without dashes"), std::string::npos);
  j = base;
  j["lossy"] = 1000;  // per mille: 1000 would drop everything
  EXPECT_NE(message(j).find("\"lossy\""), std::string::npos) << message(j);
  // A whole-number key refuses what its type cannot hold instead of casting it (undefined for 1e90).
  for (const json& unholdable : {json(1e90), json(32.5)}) {
    j = base;
    j["grid"] = unholdable;
    EXPECT_NE(message(j).find("whole number"), std::string::npos) << unholdable << ": " << message(j);
  }
}

TEST(RunConfig, PrintedConfigReadsBackToTheSameRun) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["grid"] = 32;
  const RunConfig once = from_json(j);
  const RunConfig twice = from_json(to_json(once));
  EXPECT_EQ(to_json(once), to_json(twice));
  EXPECT_EQ(twice.grid, 32);
}

TEST(RunConfig, VideoByDefaultAndTheMouseBladeInsteadOfTheCamera) {
  json j = default_config_json(true);
  j["recording"] = "/rec";
  auto children = plan(from_json(j));
  EXPECT_TRUE(has_pair(child(children, "viewer").args, "--video", "out/run/video.mp4"));
  j = default_config_json(true);
  j["mouse"] = true;
  children = plan(from_json(j));
  std::vector<std::string> order;
  for (const auto& c : children) order.push_back(c.node);
  EXPECT_EQ(order, (std::vector<std::string>{"sim", "viewer"})) << "the mouse blade replaces sensor and filter";
  const auto& v = child(children, "viewer").args;
  EXPECT_NE(std::find(v.begin(), v.end(), "--mouse"), v.end());
  j["headless"] = true;
  EXPECT_THROW((void)from_json(j), std::invalid_argument) << "the mouse needs a window";
  j = default_config_json(false);
  j["video"] = "run.mov";
  EXPECT_THROW((void)from_json(j), std::invalid_argument);
}

TEST(RunConfig, InProcessStartsOnePipelineWithEachNodesOwnCommandLine) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["domain"] = 7;
  const auto nodes = plan(from_json(j));
  j["in_process"] = true;
  const auto children = children_of(from_json(j));
  ASSERT_EQ(children.size(), 1u);
  const auto& pipeline = children.front();
  EXPECT_EQ(pipeline.program, "tachi-pipeline");
  EXPECT_TRUE(pipeline.finite) << "a recording's pipeline ends by itself";
  // "-- tachi-sim ARGS... -- tachi-viewer ARGS..." in the multi-process run's start order and arguments.
  std::vector<std::string> expected;
  for (const auto& node : nodes) {
    expected.push_back("--");
    expected.push_back(node.program);
    expected.insert(expected.end(), node.args.begin(), node.args.end());
  }
  EXPECT_EQ(pipeline.args, expected);

  j["recording"] = "";
  j["live"] = true;
  j["headless"] = true;
  EXPECT_FALSE(children_of(from_json(j)).front().finite) << "live and headless: runs until stopped";
  j["headless"] = false;
  EXPECT_TRUE(children_of(from_json(j)).front().finite) << "its viewer's window closing ends it";
}

TEST(RunConfig, InProcessAndSecureGiveEveryNodeThePipelineIdentity) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["secure"] = "/pki";
  j["in_process"] = true;
  for (const auto& node : plan(from_json(j))) EXPECT_TRUE(has_pair(node.args, "--identity", "pipeline")) << node.node;
  j["in_process"] = false;
  for (const auto& node : plan(from_json(j))) EXPECT_FALSE(has_pair(node.args, "--identity", "pipeline")) << node.node;
}

TEST(RunConfig, InProcessRefusesAnArgumentThatWouldSplitItsCommandLine) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  j["in_process"] = true;
  j["sim"]["material"] = "--";
  EXPECT_THROW((void)children_of(from_json(j)), std::invalid_argument);
  j["in_process"] = "yes";
  EXPECT_THROW((void)from_json(j), std::invalid_argument) << "in_process is a boolean";
}

TEST(RunConfig, TheClothHangsAboveAFloorUnlessItIsTakenAway) {
  json j = default_config_json(false);
  j["recording"] = "/rec";
  EXPECT_TRUE(has_pair(child(plan(from_json(j)), "sim").args, "--ground", "-1.5")) << "cut-off pieces come to rest";
  merge_into(j, parse_set("sim.ground=null"));
  const auto& args = child(plan(from_json(j)), "sim").args;
  EXPECT_EQ(std::find(args.begin(), args.end(), "--ground"), args.end());
}
