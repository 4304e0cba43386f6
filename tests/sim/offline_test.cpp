#include "tachi/sim/offline.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

using namespace tachi::sim;

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("tachi_sim_offline_test_" + name);
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(Offline, ParsesSquareAndRectangularGridsAndRejectsTheRest) {
  EXPECT_EQ(parse_grid("64"), (std::pair{64, 64}));
  EXPECT_EQ(parse_grid("128x32"), (std::pair{128, 32}));
  EXPECT_EQ(parse_grid("2X3"), (std::pair{2, 3}));
  for (const char* bad : {"", "x", "1", "64x", "x64", "64x1", "5000", "12a", "-4", "3x4x5", " 8"}) {
    EXPECT_FALSE(parse_grid(bad).has_value()) << bad;
  }
}

TEST(Offline, SummaryJsonHasTheContractKeysAndExtras) {
  Summary s;
  s.particles = 10;
  s.max_strain = 0.05F;
  s.extra["cuts"] = 3;
  const auto j = to_json(s);
  for (const char* key : {"particles", "springs", "triangles", "pieces", "max_strain", "steps", "step_ms_median"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["particles"], 10);
  EXPECT_EQ(j["cuts"], 3);
}

TEST(Offline, RunExportsMeshAndSummaryOfAHangingCloth) {
  OfflineOptions o;
  o.cloth.columns = 12;
  o.cloth.rows = 10;
  o.steps = 90;
  o.export_dir = fresh_dir("run");
  const Summary s = run_offline(o);
  EXPECT_EQ(s.particles, 120U);
  EXPECT_EQ(s.triangles, 2U * 11U * 9U);
  EXPECT_EQ(s.pieces, 1U);
  EXPECT_EQ(s.steps, 90);
  EXPECT_LE(s.max_strain, 0.10F);
  EXPECT_GT(s.step_ms_median, 0.0);

  std::ifstream json_file{o.export_dir / "summary.json"};
  ASSERT_TRUE(json_file.good());
  const auto j = nlohmann::json::parse(json_file);
  EXPECT_EQ(j["particles"], 120);
  EXPECT_EQ(j["springs"], s.springs);

  std::ifstream obj{o.export_dir / "cloth.obj"};
  ASSERT_TRUE(obj.good());
  std::size_t vertices = 0, faces = 0;
  for (std::string line; std::getline(obj, line);) {
    vertices += line.rfind("v ", 0) == 0 ? 1U : 0U;
    faces += line.rfind("f ", 0) == 0 ? 1U : 0U;
  }
  EXPECT_EQ(vertices, 120U);
  EXPECT_EQ(faces, s.triangles);
  std::filesystem::remove_all(o.export_dir);
}

TEST(Offline, SameSeedSameResultDifferentSeedDifferentFolds) {
  OfflineOptions o;
  o.cloth.columns = 16;
  o.cloth.rows = 16;
  o.steps = 60;
  o.export_dir = fresh_dir("seed_a");
  run_offline(o);
  auto read = [](const std::filesystem::path& p) {
    std::ifstream in{p};
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  const std::string a = read(o.export_dir / "cloth.obj");
  const std::string a_again = (run_offline(o), read(o.export_dir / "cloth.obj"));
  o.seed = 7;
  const std::string b = (run_offline(o), read(o.export_dir / "cloth.obj"));
  EXPECT_EQ(a, a_again);
  EXPECT_NE(a, b);
  std::filesystem::remove_all(o.export_dir);
}

TEST(Offline, UnwritableExportFolderIsAClearError) {
  OfflineOptions o;
  o.cloth.columns = 4;
  o.cloth.rows = 4;
  o.steps = 1;
  o.export_dir = "/proc/tachi_cannot_write_here";
  try {
    run_offline(o);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string{e.what()}.find("/proc/tachi_cannot_write_here"), std::string::npos) << e.what();
  }
}

}  // namespace
