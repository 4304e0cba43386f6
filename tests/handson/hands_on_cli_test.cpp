// tachi-sim's issue-12 flags as a user reaches them: --solver, --material and its quantities, --blade-force,
// --object / --object-pose, --object-from-recording (a fakenect recording written here with the sensor
// library), each bad value a usage error naming its flag.
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "table_ply.hpp"
#include "tachi/sensor/fakenect_recording.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace {

using namespace std::chrono_literals;

tachi::test::RunResult sim(std::vector<std::string> args) {
  args.insert(args.begin(), tachi::test::executable("tachi-sim"));
  return tachi::test::run(args, 60s);
}

nlohmann::json summary_of(const tachi::test::RunResult& r) {
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out.substr(r.out.find('{')));
}

TEST(HandsOnCli, EveryBadMaterialOrBladeValueIsOneErrorNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad{
      {{"--material", "wool"}, "--material"},
      {{"--mass-per-area", "nan"}, "--mass-per-area"},
      {{"--mass-per-area", "0"}, "--mass-per-area"},
      {{"--stretch-stiffness", "inf"}, "--stretch-stiffness"},
      {{"--shear-stiffness", "-3"}, "--shear-stiffness"},
      {{"--bend-stiffness", "5"}, "--bend-stiffness"},
      {{"--damping", "1000"}, "--damping"},
      {{"--blade-force", "nan"}, "--blade-force"},
      {{"--solver", "verlet"}, "--solver"},
      {{"--object-pose", "1,2"}, "--object-pose"},
      {{"--object", "/nonexistent.ply"}, "--object"},
  };
  for (const auto& [args, flag] : bad) {
    std::vector<std::string> argv{"--offline", "--steps", "1"};
    argv.insert(argv.end(), args.begin(), args.end());
    const auto r = sim(argv);
    EXPECT_NE(r.exit_code, 0) << args[0] << " " << args[1];
    EXPECT_NE(r.err.find(flag), std::string::npos) << r.err;
  }
}

TEST(HandsOnCli, ProvotSolverAndMaterialRunAndReportThemselves) {
  const auto j = summary_of(sim({"--offline", "--grid", "16", "--steps", "60", "--solver", "provot", "--material", "denim"}));
  EXPECT_EQ(j.at("solver"), "provot");
  EXPECT_LE(j.at("max_strain").get<double>(), 0.101);
  const auto pbd = summary_of(sim({"--offline", "--grid", "16", "--steps", "60", "--material", "silk", "--damping", "2"}));
  EXPECT_EQ(pbd.at("solver"), "pbd");
}

TEST(HandsOnCli, ObjectFromARecordingIsItsStaticScene) {
  const tachi::test::ScratchDir dir{"object_recording"};
  {
    // Three frames of a wall 1.5 m away with a box 0.8 m away in its middle: the scene the Kinect saw.
    tachi::sensor::FakenectWriter writer{dir / "rec"};
    for (int f = 0; f < 3; ++f) {
      tachi::sensor::DepthFrame frame;
      frame.frame = static_cast<std::uint64_t>(f);
      frame.stamp_ns = 1'700'000'000'000'000'000 + f * 33'333'333;
      frame.device_timestamp = static_cast<std::uint32_t>(f);
      frame.raw.assign(tachi::sensor::kDepthPixels, 0);
      for (int v = 0; v < tachi::sensor::kDepthHeight; ++v) {
        for (int u = 0; u < tachi::sensor::kDepthWidth; ++u) {
          const bool box = std::abs(u - 320) < 60 && std::abs(v - 240) < 60;
          const double z = box ? 0.8 : 1.5;
          frame.raw[static_cast<std::size_t>(v * tachi::sensor::kDepthWidth + u)] =
              static_cast<std::uint16_t>(std::lround((1.0 / z - 3.3309495161) / -0.0030711016));
        }
      }
      writer.write_depth(frame);
    }
  }
  const auto j = summary_of(sim({"--offline", "--grid", "8", "--steps", "30", "--object-from-recording", (dir / "rec").string()}));
  // Every 4th pixel of 640 x 480 has a reading.
  EXPECT_EQ(j.at("object_points").get<int>(), 160 * 120);

  const auto missing = sim({"--offline", "--steps", "1", "--object-from-recording", (dir / "nothing").string()});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("--object-from-recording"), std::string::npos) << missing.err;
}

TEST(HandsOnCli, APlyObjectHoldsTheClothUp) {
  const tachi::test::ScratchDir dir{"object_cli"};
  // A 1.2 m square table of points, 2 cm apart, ascii PLY, placed 0.3 m below the cloth's centre and
  // turned flat (the cloth hangs in x-y; the table is made in x-y and turned 90 degrees about x).
  tachi::test::write_table_ply(dir / "table.ply", 30, 0.02);
  const auto with = summary_of(sim({"--offline", "--grid", "16", "--pin", "none", "--steps", "60", "--object",
                                    (dir / "table.ply").string(), "--object-pose", "0,-0.8,0,90,0,0"}));
  const auto without = summary_of(sim({"--offline", "--grid", "16", "--pin", "none", "--steps", "60"}));
  EXPECT_EQ(with.at("object_points").get<int>(), 61 * 61);
  EXPECT_GT(with.at("lowest_y_m").get<double>(), -0.85) << "held up by the table";
  EXPECT_LT(without.at("lowest_y_m").get<double>(), -2.0) << "falls freely without it";
}

}  // namespace
