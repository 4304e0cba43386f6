// tachi-sim --offline as a process: the files it writes and the one-line errors for bad flags.
#include "paths.hpp"
#include "process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

using namespace std::chrono_literals;

TEST(SimOfflineCli, WritesObjAndSummaryWithTheContractKeys) {
  const auto dir = std::filesystem::temp_directory_path() / "tachi_sim_offline_cli_test";
  std::filesystem::remove_all(dir);
  const auto r = tachi::test::run({tachi::test::executable("tachi-sim"), "--offline", "--grid", "24", "--pin", "corners", "--steps", "60",
                                   "--export", dir.string()},
                                  30s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in{dir / "summary.json"};
  ASSERT_TRUE(in.good());
  const auto j = nlohmann::json::parse(in);
  for (const char* key : {"particles", "springs", "triangles", "pieces", "max_strain", "steps", "step_ms_median"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["particles"], 24 * 24);
  EXPECT_EQ(j["triangles"], 2 * 23 * 23);
  EXPECT_EQ(j["pieces"], 1);
  EXPECT_EQ(j["steps"], 60);
  EXPECT_LE(j["max_strain"].get<double>(), 0.10);
  EXPECT_TRUE(std::filesystem::file_size(dir / "cloth.obj") > 0);
  std::filesystem::remove_all(dir);
}

TEST(SimOfflineCli, BadFlagsGiveOneErrorNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--grid", "1x5"}, "--grid"},     {{"--grid", "abc"}, "--grid"},   {{"--pin", "left"}, "--pin"},
      {{"--steps", "-3"}, "--steps"},    {{"--size-m", "0"}, "--size-m"}, {{"--sphere", "0", "0", "1"}, "--sphere"},
      {{"--substeps", "0"}, "--substeps"},
  };
  for (const auto& [args, flag] : cases) {
    std::vector<std::string> argv{tachi::test::executable("tachi-sim"), "--offline"};
    argv.insert(argv.end(), args.begin(), args.end());
    const auto r = tachi::test::run(argv, 10s);
    EXPECT_EQ(r.exit_code, 2) << flag;
    EXPECT_NE(r.err.find(flag), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  }
}

}  // namespace
