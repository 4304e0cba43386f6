// Multi-process: runs the real tachi-sim --offline with a --stroke and checks what it writes.
#include "paths.hpp"
#include "process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class CutCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tachi_cut_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A horizontal stroke at height y from x = -0.6 to 0.6 (past both edges of the 1 m cloth), 1 s long.
  fs::path write_stroke(double y, const std::string& extra_rows = "") {
    const fs::path file = dir_ / "stroke.csv";
    std::ofstream out{file};
    out << "t,x,y,z\n" << extra_rows;
    for (int i = 0; i <= 60; ++i) out << 0.2 + i / 60.0 << ',' << -0.6 + 1.2 * i / 60.0 << ',' << y << ",0.01\n";
    return file;
  }

  /// The run's summary, checked for a cut that left two pieces, one fallen, the held one within the limit.
  static nlohmann::json one_piece_fell_and_rests(const fs::path& out) {
    std::ifstream in{out / "summary.json"};
    auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j.at("pieces").get<int>(), 2);
    EXPECT_EQ(j.at("fallen_pieces").get<int>(), 1) << "the cut-off piece fell";
    EXPECT_LE(j.at("max_strain").get<double>(), 0.10);
    return j;
  }

  tachi::test::RunResult sim(const std::vector<std::string>& args) {
    std::vector<std::string> argv{tachi::test::executable("tachi-sim")};
    argv.insert(argv.end(), args.begin(), args.end());
    return tachi::test::run(argv, 60s);
  }

  fs::path dir_;
};

TEST_F(CutCli, FullWidthStrokeCutsOffTheLowerPieceWhichFalls) {
  // Seed 000's cut along the grid line (--cut-mode grid reproduces it).
  const fs::path stroke = write_stroke(-0.1);
  const fs::path out = dir_ / "out";
  const auto r = sim({"--offline", "--cut-mode", "grid", "--grid", "64", "--pin", "top-edge", "--stroke", stroke.string(), "--blade",
                      "scalpel", "--steps", "300", "--export", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in{out / "summary.json"};
  ASSERT_TRUE(in.good());
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("pieces").get<int>(), 2);
  EXPECT_EQ(j.at("fallen_pieces").get<int>(), 1);
  EXPECT_EQ(j.at("cut_particles").get<int>(), 64);  // every particle of the row, edges included
  EXPECT_NEAR(j.at("cut_length_m").get<double>(), 1.0, 1e-4);
  const auto& line = j.at("cut_line");
  ASSERT_EQ(line.size(), 64U);
  EXPECT_EQ(line.front(), (nlohmann::json{0, 38}));  // y = -0.1 m is row 37.8
  EXPECT_EQ(line.back(), (nlohmann::json{63, 38}));
  EXPECT_EQ(j.at("particles").get<int>(), 64 * 64 + 64);
  EXPECT_EQ(j.at("blade").get<std::string>(), "scalpel");
  // The mesh holds every particle and the cut-off piece fell far below the pinned one.
  std::ifstream obj{out / "cloth.obj"};
  ASSERT_TRUE(obj.good());
  std::string text;
  int vertices = 0;
  double lowest = 0.0;
  while (std::getline(obj, text)) {
    if (text.rfind("v ", 0) == 0) {
      ++vertices;
      double x = 0.0;
      double y = 0.0;
      double z = 0.0;
      std::sscanf(text.c_str(), "v %lf %lf %lf", &x, &y, &z);
      lowest = std::min(lowest, y);
    }
  }
  EXPECT_EQ(vertices, 64 * 64 + 64);
  EXPECT_LT(lowest, -5.0);  // ~4 s of free fall
}

TEST_F(CutCli, ExactModeFollowsTheStrokeAndExportsPiecesAndThePattern) {
  // Between two rows (y = 0 on an even grid is half-way between rows 31 and 32): the grid mode
  // zig-zags there; the exact mode cuts straight along the stroke.
  const fs::path stroke = write_stroke(0.0);
  const fs::path out = dir_ / "out";
  const auto r = sim({"--offline", "--cut-mode", "exact", "--grid", "64", "--pin", "top-edge", "--stroke",
                      stroke.string(), "--steps", "600", "--export", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in{out / "summary.json"};
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("cut_mode").get<std::string>(), "exact");
  EXPECT_EQ(j.at("pieces").get<int>(), 2);
  EXPECT_EQ(j.at("fallen_pieces").get<int>(), 1);
  EXPECT_LE(j.at("cut_deviation_cells_max").get<double>(), 0.1);
  EXPECT_NEAR(j.at("cut_length_m").get<double>(), 1.0, 0.02);
  EXPECT_LE(j.at("max_strain").get<double>(), 0.10);
  EXPECT_GE(j.at("step_ms_max").get<double>(), j.at("step_ms_median").get<double>());
  // cloth.obj: one group per piece that has faces, and a normal per vertex.
  std::ifstream obj{out / "cloth.obj"};
  std::string text;
  int groups = 0;
  int normals = 0;
  int vertices = 0;
  while (std::getline(obj, text)) {
    groups += text.rfind("g piece_", 0) == 0 ? 1 : 0;
    normals += text.rfind("vn ", 0) == 0 ? 1 : 0;
    vertices += text.rfind("v ", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(groups, 2);
  EXPECT_EQ(normals, vertices);
  // pattern.svg: the two pieces' outlines and the cut path, in millimetres (the cloth is 1000 mm wide).
  std::ifstream svg{out / "pattern.svg"};
  ASSERT_TRUE(svg.good());
  const std::string pattern{std::istreambuf_iterator<char>{svg}, std::istreambuf_iterator<char>{}};
  std::size_t pieces = 0;
  for (std::size_t at = pattern.find("id=\"piece_"); at != std::string::npos; at = pattern.find("id=\"piece_", at + 1)) {
    ++pieces;
  }
  EXPECT_EQ(pieces, 2U);
  // Each piece is one closed outline (one subpath, "M ... Z"), not loose two-point segments: a cutter or
  // Inkscape fills and offsets it.
  for (std::size_t at = pattern.find("id=\"piece_"); at != std::string::npos; at = pattern.find("id=\"piece_", at + 1)) {
    const auto d = pattern.find(" d=\"", at) + 4;
    const std::string path = pattern.substr(d, pattern.find('"', d) - d);
    EXPECT_EQ(std::count(path.begin(), path.end(), 'M'), 1) << path.substr(0, 200);
    EXPECT_EQ(std::count(path.begin(), path.end(), 'Z'), 1) << path.substr(0, 200);
  }
  EXPECT_NE(pattern.find("class=\"cut\""), std::string::npos);
  EXPECT_NE(pattern.find("1000.00 "), std::string::npos);
}

TEST_F(CutCli, ASlitStaysWithinTenPercentStrainInEveryModeOverJitterSeeds) {
  // The target "max strain at rest <= 10 % after cuts in every mode", through the CLI as a user runs it, with
  // tachi-sim's 0.1 mm out-of-plane jitter: a 0.65 m slit a little below the middle of a 64 x 64 cloth
  // pinned along its top edge. The piece below the slit swings out of the plane and hangs from the slit's two
  // tips. Before the attachments held it from both tips and anchored only where a path can bend, this rested at
  // exact 21.7 %, grid 10.8 %, delete 17.8 %, and the exact and delete pieces never came to rest. At 128 x 128
  // the lip next to each tip hangs from that tip alone and carries the piece's weight along ~30 springs, more
  // than Provot's six sweeps settle: grid 14.2 % and delete 12.5 % until the sweeps went on locally.
  const fs::path stroke = dir_ / "slit.csv";
  {
    std::ofstream out{stroke};
    out << "t,x,y,z\n";
    for (int i = 0; i <= 32; ++i) out << 0.5 + 0.02 * i << ',' << -0.325 + 0.65 * i / 32.0 << ",-0.05,0\n";
  }
  const auto run = [&](const std::string& grid, const std::string& mode, int seed) {
    const fs::path out = dir_ / ("out_" + grid + "_" + mode + "_" + std::to_string(seed));
    const auto r = sim({"--offline", "--cut-mode", mode, "--grid", grid, "--pin", "top-edge", "--stroke", stroke.string(),
                        "--steps", "900", "--seed", std::to_string(seed), "--export", out.string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in{out / "summary.json"};
    const auto j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded()) {
      ADD_FAILURE() << "no summary.json";
      return 1.0;
    }
    EXPECT_GT(j.at("topology_version").get<int>(), 0) << "the stroke cut";
    // One slit: one piece of cloth, nothing fallen, in every mode. Delete mode's completeCUT particles, in no
    // triangle, are loose particles, not pieces (they were reported as fallen pieces before session 31).
    EXPECT_EQ(j.at("pieces").get<int>(), 1);
    EXPECT_EQ(j.at("fallen_pieces").get<int>(), 0);
    if (mode == "delete") {
      EXPECT_GT(j.at("loose_particles").get<int>(), 0);
    } else {
      EXPECT_EQ(j.at("loose_particles").get<int>(), 0);
    }
    EXPECT_LE(j.at("max_strain").get<double>(), 0.10);
    return j.at("held_kinetic_energy_j").get<double>();
  };
  // At rest, not a snapshot of a swinging cloth: the pinned piece's kinetic energy after 15 s (it was 4e-4 J
  // in exact mode while a lip fluttered; 1e-7 J and less now). 15 s, not 10: the piece's swing after the cut
  // decays smoothly, and where it stands at exactly 10 s depends on the step each sample lands in. Exact and
  // grid rest on every jitter seed (0 of 50 seeds at 64 x 64 and 0 of 25 at 128 x 128 kept moving).
  for (const std::string mode : {"exact", "grid"}) {
    for (const int seed : {1, 2, 3}) {
      SCOPED_TRACE("64 x 64, " + mode + ", seed " + std::to_string(seed));
      EXPECT_LT(run("64", mode, seed), 1e-5);
    }
    SCOPED_TRACE("128 x 128, " + mode);
    EXPECT_LT(run("128", mode, 1), 1e-5);
  }
  // Delete mode's slit does not always rest: a known defect (docs/sim.md, Limits). On some jitter seeds the
  // lip below the slit keeps moving out of the plane (~1e-5 J at 15 s, 0.1-0.2 m/s at the lip's particles;
  // seed 1 at 64 x 64 still 1.5e-5 J after 60 s). Seeds 1-50 at 64 x 64: 11 with the cut's work spread (the
  // default), 20 with it in the cut's step; seeds 1-25 at 128 x 128: 7 and 6. So the check is over seeds:
  // of seeds 1-12 (4 keep moving now) at most 6 may, where the measured rate (11 in 50) leaves 0.7 % for 7
  // or more; and none may move much (the most over those 75 seeds: 3.6e-5 J; the lip's flutter before the
  // anchors: 2e-3 J). The strain stays within the limit on every seed.
  int moving = 0;
  for (int seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE("64 x 64, delete, seed " + std::to_string(seed));
    const double energy = run("64", "delete", seed);
    EXPECT_LT(energy, 1e-4);
    moving += energy >= 1e-5 ? 1 : 0;
  }
  EXPECT_LE(moving, 6) << "delete-mode slits that keep moving, of 12 jitter seeds (measured: 11 in 50)";
  SCOPED_TRACE("128 x 128, delete");
  EXPECT_LT(run("128", "delete", 1), 1e-4);
}

TEST_F(CutCli, ACutsTetherWorkSpreadOverStepsStillDropsThePiece) {
  // --cut-work-per-step: what a cut's tether work does in the cut's step (docs/sim.md "Caches"); the rest
  // is spread over the next steps, the cut-off piece held on its old tethers until it is labelled. The piece
  // must still fall, whole, and the cloth rest as when all of it is done at once (0; the default is 1).
  const fs::path stroke = write_stroke(-0.1);
  for (const std::string budget : {"0", "1", "4096"}) {
    SCOPED_TRACE(budget);
    const fs::path out = dir_ / ("out_" + budget);
    const auto r = sim({"--offline", "--cut-mode", "exact", "--grid", "64", "--pin", "top-edge", "--stroke", stroke.string(),
                        "--steps", "300", "--cut-work-per-step", budget, "--export", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    one_piece_fell_and_rests(out);
  }
  const auto bad = sim({"--offline", "--grid", "8", "--steps", "1", "--cut-work-per-step", "-5"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--cut-work-per-step"), std::string::npos) << bad.err;
}

TEST_F(CutCli, TheRepairsBudgetSpreadsTheTethersRepairOverMoreSteps) {
  // --repair-per-step / --repair-share: how many particles the tethers' repair after a cut settles a step
  // (docs/sim.md "Caches"). A budget of one particle a step must stretch the repair over most of the run
  // (summary: tether_repair_steps), and the piece must still fall and the cloth come to rest within the limit.
  const fs::path stroke = write_stroke(0.25);
  std::map<std::string, std::int64_t> repair_steps;
  for (const std::string budget : {"default", "1"}) {
    SCOPED_TRACE(budget);
    const fs::path out = dir_ / ("out_" + budget);
    std::vector<std::string> args{"--offline", "--cut-mode", "exact", "--grid", "64", "--pin", "top-edge",
                                  "--stroke", stroke.string(), "--steps", "300", "--export", out.string()};
    if (budget != "default") args.insert(args.end(), {"--repair-per-step", budget, "--repair-share", "0"});
    const auto r = sim(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = one_piece_fell_and_rests(out);
    repair_steps[budget] = j.at("tether_repair_steps").get<std::int64_t>();
  }
  // Measured: 60 steps (the stroke's second, while its cuts go on) against 281 of 300.
  EXPECT_GT(repair_steps["default"], 0);
  EXPECT_LT(repair_steps["default"], 120);
  EXPECT_GT(repair_steps["1"], 200);
  for (const std::string flag : {"--repair-per-step", "--repair-share"}) {
    const auto bad = sim({"--offline", "--grid", "8", "--steps", "1", flag, "-1"});
    EXPECT_EQ(bad.exit_code, 2) << flag;
    EXPECT_NE(bad.err.find(flag), std::string::npos) << bad.err;
  }
}

TEST_F(CutCli, BadCutModeIsAUsageError) {
  const auto r = sim({"--offline", "--grid", "8", "--cut-mode", "laser", "--steps", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--cut-mode"), std::string::npos) << r.err;
}

TEST_F(CutCli, NoStrokeMeansNoCut) {
  const fs::path out = dir_ / "out";
  const auto r = sim({"--offline", "--grid", "16", "--pin", "top-edge", "--steps", "10", "--export", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in{out / "summary.json"};
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("pieces").get<int>(), 1);
  EXPECT_EQ(j.at("fallen_pieces").get<int>(), 0);
  EXPECT_EQ(j.at("cut_particles").get<int>(), 0);
  EXPECT_TRUE(j.at("cut_line").empty());
}

TEST_F(CutCli, BadBladeIsAUsageError) {
  const auto r = sim({"--offline", "--grid", "8", "--blade", "sword", "--steps", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--blade"), std::string::npos) << r.err;
}

TEST_F(CutCli, MissingStrokeFileIsAUsageError) {
  const auto r = sim({"--offline", "--grid", "8", "--stroke", (dir_ / "nope.csv").string(), "--steps", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--stroke"), std::string::npos) << r.err;
}

TEST_F(CutCli, StrokeWithoutHeaderFailsWithTheReason) {
  const fs::path file = dir_ / "bad.csv";
  std::ofstream{file} << "0,0,0,0\n";
  const auto r = sim({"--offline", "--grid", "8", "--stroke", file.string(), "--steps", "1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("t,x,y,z"), std::string::npos) << r.err;
}

TEST_F(CutCli, BadRowsAreSkippedAndCounted) {
  const fs::path stroke = write_stroke(0.0, "0.1,oops,0,0\n");
  const fs::path out = dir_ / "out";
  const auto r = sim({"--offline", "--grid", "16", "--pin", "top-edge", "--stroke", stroke.string(), "--steps", "90",
                      "--export", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in{out / "summary.json"};
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("stroke_rows_skipped").get<int>(), 1);
  EXPECT_EQ(j.at("pieces").get<int>(), 2);
}

// cut_stability --keep-strokes (bench/sim/cut_stability.cpp) keeps each pair of strokes that cut differently,
// with the two tachi-sim runs that cut them as it did: what a user runs to look at a flip. Run from the
// folder, they must give the pieces and cut lengths cut_stability reported.
TEST_F(CutCli, CutStabilitysKeptStrokesCutTheSameThroughTachiSim) {
  const fs::path keep = dir_ / "keep";
  const auto r = tachi::test::run({tachi::test::executable("cut_stability"), "--strokes", "40", "--first-seed", "261",
                                   "--recut", "--blade", "razor", "--mode", "exact", "--keep-strokes", keep.string()},
                                  300s);
  ASSERT_EQ(r.exit_code, 1) << r.out << r.err;  // some of them cut differently gone over again
  std::vector<fs::path> notes;
  for (const auto& entry : fs::directory_iterator(keep)) {
    if (entry.path().extension() == ".txt") notes.push_back(entry.path());
  }
  // 6 of the first 40 strokes cut differently when this was written, none of them since the blade rides in its
  // slit (session 39), and stroke 51 no longer since a stroke turning back along its cut is in its slit (session
  // 40); strokes 101-140 (111, 115, 135, 140) no longer since a blade in its slit is where its hand cut (session
  // 41); strokes 141-180 (166) no longer since a pass ends where the hand turned back (session 42); of strokes
  // 261-300, 279 still does. If none of these does, the re-cut target may be met here: take a range that still
  // differs, or drop this test with the target.
  ASSERT_FALSE(notes.empty()) << r.out;
  std::sort(notes.begin(), notes.end());
  std::ifstream note{notes.front()};
  std::vector<std::string> commands(2);
  std::string said;
  ASSERT_TRUE(std::getline(note, commands[0]) && std::getline(note, commands[1]) && std::getline(note, said))
      << notes.front();
  std::size_t pieces[2] = {};
  double lengths[2] = {};
  ASSERT_EQ(std::sscanf(said.c_str(), "# cut_stability: %zu pieces %lf m once, %zu pieces %lf m", &pieces[0],
                        &lengths[0], &pieces[1], &lengths[1]),
            4)
      << said;
  for (std::size_t k = 0; k < 2; ++k) {
    std::istringstream words{commands[k]};
    std::vector<std::string> argv;
    std::string export_dir;
    for (std::string w; words >> w;) {
      if (argv.empty()) {
        ASSERT_EQ(w, "tachi-sim") << commands[k];
        w = tachi::test::executable("tachi-sim");
      } else if (argv.back() == "--stroke" || argv.back() == "--export") {
        w = (keep / w).string();  // the note's paths are the folder's
        if (argv.back() == "--export") export_dir = w;
      }
      argv.push_back(w);
    }
    const auto sim = tachi::test::run(argv, 120s);
    ASSERT_EQ(sim.exit_code, 0) << commands[k] << "\n" << sim.err;
    const auto summary = nlohmann::json::parse(std::ifstream{fs::path{export_dir} / "summary.json"});
    EXPECT_EQ(summary.at("pieces").get<std::size_t>(), pieces[k]) << commands[k];
    EXPECT_NEAR(summary.at("cut_length_m").get<double>(), lengths[k], 1e-4) << commands[k];
  }
  EXPECT_TRUE(pieces[0] != pieces[1] || std::abs(lengths[0] - lengths[1]) > 0.01 * lengths[0]) << said;
}

}  // namespace
