#include "paths.hpp"
#include "tachi/sensor/synthetic.hpp"

#include <gtest/gtest.h>

#include "tachi/sensor/hand_csv.hpp"
#include "test_util.hpp"

namespace tachi::sensor {
namespace {

ScenarioSpec short_spec() {
  ScenarioSpec s;
  s.name = "unit";
  s.seed = 7;
  s.path = {{0.0, Eigen::Vector3d::Zero(), true}, {0.2, {-0.1, 0.0, 0.98}, false}, {0.4, {0.1, 0.05, 0.98}, false}};
  return s;
}

TEST(SyntheticScene, SameSeedSameFramesOtherSeedOtherNoise) {
  SyntheticScene a(short_spec()), b(short_spec());
  auto other = short_spec();
  other.seed = 8;
  SyntheticScene c(other);
  GroundTruth ta, tb, tc;
  for (std::uint64_t i = 0; i < a.frame_count(); ++i) {
    const auto fa = a.render(i, ta), fb = b.render(i, tb), fc = c.render(i, tc);
    EXPECT_EQ(fa.raw, fb.raw);
    EXPECT_NE(fa.raw, fc.raw);
    EXPECT_EQ(ta.palm, tc.palm);  // noise differs, the scene does not
  }
  EXPECT_EQ(a.frame_count(), 13u);  // 0.4 s at 30 fps, both ends included
}

TEST(SyntheticScene, RendersKinectEffectsAndConsistentTruth) {
  SyntheticScene scene(short_spec());
  GroundTruth truth;
  DepthFrame frame;
  for (std::uint64_t i = 0; i < scene.frame_count(); ++i) frame = scene.render(i, truth);
  const DepthModel model;
  ASSERT_TRUE(truth.visible);
  EXPECT_NEAR((model.project(truth.palm) - truth.pixel).norm(), 0.0, 1e-9);
  // Integer disparity of the palm at the palm centre pixel, within noise of the true depth.
  const auto u = static_cast<int>(std::lround(truth.pixel.x())), v = static_cast<int>(std::lround(truth.pixel.y()));
  int near_truth = 0;
  for (int dv = -3; dv <= 3; ++dv)
    for (int du = -3; du <= 3; ++du) {
      const auto raw = frame.at(u + du, v + dv);
      if (raw != kNoReading && std::abs(model.metres(raw) - truth.palm.z()) < 0.01) ++near_truth;
    }
  EXPECT_GE(near_truth, 40);
  // The invalid band at the left edge.
  for (int y = 0; y < kDepthHeight; y += 7)
    for (int x = 0; x < 8; ++x) EXPECT_EQ(frame.at(x, y), kNoReading);
  // IR shadow: no readings just left of the hand (the projector is to the right), readings to its right.
  int left_holes = 0, right_holes = 0;
  for (int dv = -10; dv <= 10; ++dv) {
    int x = u;
    while (x > 8 && frame.at(x, v + dv) != kNoReading && std::abs(model.metres(frame.at(x, v + dv)) - truth.palm.z()) < 0.1) --x;
    for (int k = 0; k < 5; ++k) left_holes += frame.at(x - k, v + dv) == kNoReading;
    x = u;
    while (x < 639 && frame.at(x, v + dv) != kNoReading && std::abs(model.metres(frame.at(x, v + dv)) - truth.palm.z()) < 0.1) ++x;
    for (int k = 2; k < 7; ++k) right_holes += frame.at(std::min(639, x + k), v + dv) == kNoReading;
  }
  EXPECT_GT(left_holes, 3 * right_holes + 20);
}

TEST(SyntheticScene, RestingHandIsNotVisible) {
  auto spec = short_spec();
  spec.path = {{0.0, Eigen::Vector3d::Zero(), true}, {0.1, Eigen::Vector3d::Zero(), true}};
  SyntheticScene scene(spec);
  GroundTruth truth;
  scene.render(0, truth);
  EXPECT_FALSE(truth.visible);
}

// The hanging rest (spec.hanging_rest, the randomized world's): the resting hand is at the end of the
// arm (within its length and the hand's 6 cm of the shoulder; the floating rest lies 0.73 m from it,
// beyond the arm's 0.59 m), fingers down, and a target below the shoulder out of reach is drawn where
// the arm ends, not detached below it. The resting and the lowered hand are neither raised nor visible.
TEST(SyntheticScene, AHangingHandRestsAtTheArmsEnd) {
  auto spec = short_spec();
  const Eigen::Vector3d shoulder(-0.19, 0.0, 1.44);
  EXPECT_GT((SyntheticScene(spec).rest_palm() - shoulder).norm(), 0.7);  // the floating rest, for the bundled scenes
  spec.hanging_rest = true;
  spec.path = {{0.0, Eigen::Vector3d::Zero(), true}, {0.5, Eigen::Vector3d::Zero(), true}, {1.0, {-0.2, 1.0, 1.42}, false}};
  SyntheticScene scene(spec);
  const Eigen::Vector3d rest = scene.rest_palm();
  EXPECT_LT((rest - shoulder).norm(), 0.59 + 0.065);
  EXPECT_GT((rest - shoulder).norm(), 0.59);
  EXPECT_GT(rest.y(), 0.6);  // below the shoulder, the palm's centre below the wrist (fingers down)
  GroundTruth truth;
  scene.render(0, truth);
  EXPECT_FALSE(truth.raised);
  EXPECT_FALSE(truth.visible);
  EXPECT_LT((truth.palm - rest).norm(), 0.02);  // the body sways; the hand stays on the arm
  for (std::uint64_t i = 1; i < scene.frame_count(); ++i) scene.render(i, truth);
  EXPECT_LT((truth.palm - shoulder).norm(), 0.59 + 0.065 + 0.02);  // the target 1 m below: where the arm reaches
  EXPECT_GT((truth.intended - shoulder).norm(), 0.9);
}

TEST(SyntheticScene, WritesARecordingAndGroundTruth) {
  test::ScratchDir dir("synth");
  const auto frames = write_synthetic_recording(short_spec(), dir.path() / "rec");
  const auto truth = read_truth_csv(dir.path() / "rec" / "ground_truth.csv");
  ASSERT_EQ(truth.size(), frames);
  EXPECT_EQ(truth.front().stamp_ns, 1'700'000'000'000'000'000LL);
  EXPECT_EQ(truth[3].stamp_ns, 1'700'000'000'100'000'000LL);
  EXPECT_FALSE(truth.front().visible);
  EXPECT_TRUE(truth.back().visible);
}

TEST(ScenarioSpec, BundledSpecsLoad) {
  const auto names = test::scenario_names();
  EXPECT_GE(names.size(), 11u);
  for (const auto& name : names) {
    const auto spec = load_scenario(std::filesystem::path(tachi::test::source_dir() + "/recordings/scenarios") / (name + ".json"));
    EXPECT_EQ(spec.name, name);
    EXPECT_GE(spec.path.size(), 2u);
  }
}

TEST(ScenarioSpec, BadSpecsNameTheKey) {
  test::ScratchDir dir("spec");
  const auto error = [&](const std::string& text) {
    test::write_text(dir.path() / "s.json", text);
    try {
      load_scenario(dir.path() / "s.json");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string path = R"("path": [{"t": 0, "rest": true}, {"t": 1, "p": [0, 0, 1]}])";
  EXPECT_EQ(error(R"({"name": "x", )" + path + "}"), "no error");
  EXPECT_NE(error(R"({)" + path + "}").find("\"name\""), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "fps": 0, )" + path + "}").find("\"fps\""), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "path": [{"t": 0, "rest": true}]})").find("at least two"), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "path": [{"t": 0, "rest": true}, {"t": 0, "rest": true}]})").find("increase"), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "path": [{"t": 0, "rest": true}, {"t": 1, "p": [0, 0]}]})").find("needs \"p\""), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "path": [{"t": 0, "rest": true}, {"t": 1, "p": [0, 0, 9]}]})").find("z must be"), std::string::npos);
  EXPECT_NE(error(R"({"name": "x", "jitter_m": "a", )" + path + "}").find("\"jitter_m\""), std::string::npos);
  EXPECT_EQ(error(R"({"name": "x", "resting": "hanging", )" + path + "}"), "no error");
  EXPECT_NE(error(R"({"name": "x", "resting": "down", )" + path + "}").find("\"resting\""), std::string::npos);
}

}  // namespace
}  // namespace tachi::sensor
