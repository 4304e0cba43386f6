// Multi-process: a stroke CSV with a row no hand can reach (2-100 m off the cloth within one 1/60 s
// sample) goes through the real tachi-sim --offline --stroke: the row is an outlier (the filter's 10 m/s
// rule, common/hand_speed.hpp), counted in the summary, and the cut is the clean slit the same stroke
// without it makes.
#include "paths.hpp"
#include "process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

struct Outcome {
  int pieces = 0;
  double cut_length_m = 0.0;
  int outliers = 0;
};

class StrokeOutlierCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tachi_outlier_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A 0.6 m slit at y = -0.1 (x from -0.3 to 0.3, inside the cloth), 1 s at 60 Hz, 1 cm in front; with
  /// `far_m` > 0 the sample at `far_row` is moved that far off along (dx, dy, dz).
  fs::path write_slit(const std::string& name, int far_row, double far_m, const Eigen::Vector3d& direction) const {
    const fs::path file = dir_ / name;
    std::ofstream out{file};
    out << "t,x,y,z\n";
    for (int i = 0; i <= 60; ++i) {
      Eigen::Vector3d p{-0.3 + 0.6 * i / 60.0, -0.1, 0.01};
      if (i == far_row) p += far_m * direction.normalized();
      out << 0.2 + i / 60.0 << ',' << p.x() << ',' << p.y() << ',' << p.z() << '\n';
    }
    return file;
  }

  Outcome cut(const fs::path& stroke, const std::string& mode) const {
    const fs::path out = dir_ / ("out_" + mode);
    const auto r = tachi::test::run({tachi::test::executable("tachi-sim"), "--offline", "--cut-mode", mode, "--grid", "32", "--pin", "top-edge",
                                     "--stroke", stroke.string(), "--blade", "razor", "--steps", "150", "--export",
                                     out.string()},
                                    60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in{out / "summary.json"};
    const auto j = nlohmann::json::parse(in);
    return {j.at("pieces").get<int>(), j.at("cut_length_m").get<double>(), j.at("stroke_outliers").get<int>()};
  }

  fs::path dir_;
};

TEST_F(StrokeOutlierCli, ARowMetresAwayIsAnOutlierCountedAndNeverCutAlong) {
  std::mt19937 rng{20261203U};
  std::uniform_real_distribution<double> unit{-1.0, 1.0};
  std::uniform_real_distribution<double> far{2.0, 100.0};
  std::uniform_int_distribution<int> row{5, 55};
  for (const std::string mode : {"exact", "grid", "delete"}) {
    const Outcome clean = cut(write_slit("clean.csv", -1, 0.0, Eigen::Vector3d::UnitX()), mode);
    EXPECT_EQ(clean.outliers, 0) << mode;
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::Vector3d direction{unit(rng), unit(rng), unit(rng)};
      const double distance = far(rng);
      const int at = row(rng);
      const Outcome spiked = cut(write_slit("spiked.csv", at, distance, direction), mode);
      SCOPED_TRACE(mode + ": row " + std::to_string(at) + " moved " + std::to_string(distance) + " m");
      EXPECT_EQ(spiked.outliers, 1);
      EXPECT_EQ(spiked.pieces, clean.pieces);
      EXPECT_NEAR(spiked.cut_length_m, clean.cut_length_m, 0.01 * clean.cut_length_m + 0.02);
    }
  }
}

}  // namespace
