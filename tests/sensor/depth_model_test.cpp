#include "tachi/sensor/depth_model.hpp"

#include <gtest/gtest.h>

#include "tachi/sensor/depth_frame.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

TEST(DepthModel, BurrusTableMatchesTheFormula) {
  const DepthModel m;
  for (const int r : {0, 400, 800, 1000, 1050}) {
    const auto raw = static_cast<std::uint16_t>(r);
    const double expected = 1.0 / (raw * -0.0030711016 + 3.3309495161);
    EXPECT_NEAR(m.metres(raw), expected, 1e-6) << raw;
  }
  EXPECT_NEAR(m.metres(800), 1.1438, 1e-3);  // FIELD_NOTES: raw 800 ~ 1144 mm (Burrus)
  EXPECT_EQ(m.metres(kNoReading), 0.0f);
  EXPECT_EQ(m.metres(2000), 0.0f);  // beyond the fit's pole: no depth, not a negative one
}

TEST(DepthModel, TableIsMonotonicWhereValid) {
  const DepthModel m;
  for (std::uint16_t raw = 1; raw < 1084; ++raw) EXPECT_GT(m.metres(raw), m.metres(raw - 1)) << raw;
}

TEST(DepthModel, RawAtInvertsTheFitAndPinholeRoundTrips) {
  const DepthModel m;
  for (const double z : {0.6, 1.0, 1.5, 2.8}) EXPECT_NEAR(1.0 / (m.raw_at(z) * m.fit().a + m.fit().b), z, 1e-9);
  const Eigen::Vector3d p = m.back_project(100.5, 400.25, 1.2);
  const Eigen::Vector2d uv = m.project(p);
  EXPECT_NEAR(uv.x(), 100.5, 1e-9);
  EXPECT_NEAR(uv.y(), 400.25, 1e-9);
  EXPECT_NEAR(m.back_project(m.intrinsics().cx, m.intrinsics().cy, 2.0).head<2>().norm(), 0.0, 1e-12);
}

TEST(DepthModel, CalibrationFileOverridesDefaults) {
  test::ScratchDir dir("calib");
  EXPECT_EQ(model_for_recording(dir.path()).intrinsics().fx, 594.214);
  test::write_text(dir.path() / kCalibrationFile, R"({"fx": 580.0, "cy": 250.5, "disparity_b": 3.3})");
  const DepthModel m = model_for_recording(dir.path());
  EXPECT_EQ(m.intrinsics().fx, 580.0);
  EXPECT_EQ(m.intrinsics().fy, 591.040);
  EXPECT_EQ(m.intrinsics().cy, 250.5);
  EXPECT_NEAR(m.metres(800), 1.0 / (800 * -0.0030711016 + 3.3), 1e-6);
  save_calibration(dir.path() / "copy.json", m);
  EXPECT_EQ(load_calibration(dir.path() / "copy.json").intrinsics().cy, 250.5);
}

TEST(DepthModel, BadCalibrationFilesNameTheProblem) {
  test::ScratchDir dir("badcalib");
  const auto error = [&](const std::string& text) {
    test::write_text(dir.path() / "c.json", text);
    try {
      load_calibration(dir.path() / "c.json");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("{not json").find("not JSON"), std::string::npos);
  EXPECT_NE(error(R"({"fx": "big"})").find("\"fx\" is not a number"), std::string::npos);
  EXPECT_NE(error(R"({"fy": -1})").find("must be > 0"), std::string::npos);
  EXPECT_NE(error("[1, 2]").find("JSON object"), std::string::npos);
}

}  // namespace
}  // namespace tachi::sensor
