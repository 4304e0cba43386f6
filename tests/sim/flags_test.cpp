// tachi-sim's object flags parsed in-process (sim/flags.cpp): --workspace-config gives --object-from-recording
// the filter's camera-to-cloth mapping, so a recorded scene lands where the filter puts the hand.
#include "flags.hpp"
#include "parse_flags.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace tachi::sim {
namespace {

ObjectOptions parse(std::vector<std::string> args) {
  return test::parse_flags<ObjectOptions>([](CLI::App& app, ObjectOptions& o) { add_object_flags(app, o); }, std::move(args));
}

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("tachi_sim_flags_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(SimFlags, WorkspaceConfigGivesTheRecordedObjectTheFiltersMapping) {
  EXPECT_TRUE(parse({}).workspace.rotation.isApprox(common::default_mapping().rotation)) << "no config: the filter's default";
  // A filter config with a camera mounted 2 m away, turned 90 degrees about z, at half scale.
  const auto config = write("filter.json", R"({"smoother": {"kind": "none"},
      "workspace": {"rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "translation_m": [0.1, 0, -2], "scale": 0.5}})");
  const ObjectOptions options = parse({"--workspace-config", config.string()});
  const Eigen::Vector3f camera{0.2F, 0.4F, 2.0F};
  const Eigen::Vector3f expected = 0.5F * (Eigen::Vector3f{-0.4F, 0.2F, 2.0F} + Eigen::Vector3f{0.1F, 0.0F, -2.0F});
  EXPECT_TRUE(options.workspace.to_world(camera).isApprox(expected, 1e-5F)) << options.workspace.to_world(camera).transpose();
  EXPECT_FALSE(options.workspace.to_world(camera).isApprox(common::default_mapping().to_world(camera), 1e-3F));
  std::filesystem::remove(config);
}

TEST(SimFlags, ABadWorkspaceConfigIsRefusedNamingTheFlagAndTheKey) {
  const auto bad = write("bad.json", R"({"workspace": {"scale": -1}})");
  try {
    (void)parse({"--workspace-config", bad.string()});
    ADD_FAILURE() << "a negative scale accepted";
  } catch (const CLI::ParseError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--workspace-config"), std::string::npos) << what;
    EXPECT_NE(what.find("scale"), std::string::npos) << what;
    EXPECT_NE(what.find(bad.string()), std::string::npos) << what;
  }
  std::filesystem::remove(bad);
  const auto not_json = write("not.json", "{");
  EXPECT_THROW((void)parse({"--workspace-config", not_json.string()}), CLI::ParseError);
  std::filesystem::remove(not_json);
}

}  // namespace
}  // namespace tachi::sim
