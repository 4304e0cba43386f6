// The object taken from a recording is placed with the workspace mapping the filter uses: with a configured
// (non-default) mapping the scene lands where the hand does, not where the default mirror would put it.
#include "scratch_dir.hpp"
#include "tachi/common/workspace.hpp"
#include "tachi/sensor/depth_frame.hpp"
#include "tachi/sensor/fakenect_recording.hpp"
#include "tachi/sim/object.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {
// Three frames of a flat wall 1.5 m from the Kinect.
void write_wall(const std::filesystem::path& dir) {
  tachi::sensor::FakenectWriter writer{dir};
  for (int f = 0; f < 3; ++f) {
    tachi::sensor::DepthFrame frame;
    frame.frame = static_cast<std::uint64_t>(f);
    frame.stamp_ns = 1'700'000'000'000'000'000 + f * 33'333'333;
    frame.device_timestamp = static_cast<std::uint32_t>(f);
    frame.raw.assign(tachi::sensor::kDepthPixels,
                     static_cast<std::uint16_t>(std::lround((1.0 / 1.5 - 3.3309495161) / -0.0030711016)));
    writer.write_depth(frame);
  }
}

Eigen::Vector3f centroid(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const auto& p : points) sum += p;
  return sum / static_cast<float>(points.size());
}
}  // namespace

TEST(ObjectWorkspace, ARecordedSceneIsMappedWithTheFiltersMapping) {
  const tachi::test::ScratchDir dir{"object_workspace"};
  write_wall(dir / "rec");
  const auto by_default = tachi::sim::scene_from_recording(dir / "rec", tachi::common::default_mapping());
  // The filter's config moved the cloth plane to 1.5 m and shifted the workspace 0.3 m to the right, at half scale.
  tachi::common::WorkspaceMapping configured = tachi::common::default_mapping(1.5F);
  configured.translation_m.x() += 0.3F;
  configured.scale = 0.5F;
  ASSERT_FALSE(tachi::common::validate(configured));
  const auto mapped = tachi::sim::scene_from_recording(dir / "rec", configured);
  ASSERT_EQ(mapped.size(), by_default.size());
  ASSERT_FALSE(mapped.empty());
  // Each point is exactly where the filter would put a hand seen at the same camera point.
  for (std::size_t i = 0; i < mapped.size(); i += 97) {
    const Eigen::Vector3f camera = tachi::common::default_mapping().to_camera(by_default[i]);
    EXPECT_TRUE(mapped[i].isApprox(configured.to_world(camera), 1e-4F)) << i;
  }
  // The wall 1.5 m away lies on the configured cloth plane (z = 0), not 0.5 m off it as with the default.
  EXPECT_NEAR(centroid(mapped).z(), 0.0F, 0.01F);
  EXPECT_NEAR(centroid(by_default).z(), 0.5F, 0.01F);
  EXPECT_NEAR(centroid(mapped).x() - 0.5F * centroid(by_default).x(), 0.15F, 0.01F);

  tachi::sim::ObjectOptions options;
  options.recording = dir / "rec";
  options.workspace = configured;
  const auto collider = tachi::sim::load_object(options);
  ASSERT_TRUE(collider);
  EXPECT_NEAR(centroid(collider->points()).z(), 0.0F, 0.01F) << "load_object uses the options' mapping";
}
