// Synthetic Kinect recordings: renders a person whose arm moves the palm along a scripted path,
// with Kinect v1 effects (integer disparity, noise, IR shadows, dropouts, invalid left band),
// into fakenect-format frames plus a ground-truth CSV of the palm centre.
//
// Scene (camera frame, metres; x right, y down, z forward): a wall at 2.8 m; a person facing the
// sensor, torso at ~1.47 m, shoulders at camera height; the active (camera-left) arm is posed by
// two-bone inverse kinematics so that the palm centre follows the path; the other arm hangs; the
// body sways a little. An optional static box (a "stand") sits nearer than the hand in the
// bottom-right corner: the hand finder must ignore it. The IR projector sits 7.5 cm to the
// camera's right (+x), so IR shadows fall on the left of near objects, as on a real Kinect.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tachi/sensor/depth_frame.hpp"
#include "tachi/sensor/depth_model.hpp"

namespace tachi::sensor {

/// A palm-centre waypoint; `rest` means the hanging position below the image.
struct Keyframe {
  double t = 0.0;  ///< seconds from the recording's start
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  bool rest = false;
};

/// A static thing of the room, an axis-aligned box (a box, a table top, a chair back, a monitor, a
/// side wall). It is there from `from_s`; when `slide_s` > 0 it slides in over that long before,
/// from `slide_from` (an offset, metres) to its place: an object moved in during the take.
struct SceneObject {
  std::string kind;
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
  double from_s = 0.0;
  double slide_s = 0.0;
  Eigen::Vector3d slide_from = Eigen::Vector3d::Zero();
};

struct ScenarioSpec {
  std::string name;
  std::string description;
  std::uint64_t seed = 1;
  double fps = 30.0;
  std::vector<Keyframe> path;     ///< at least two, increasing t; monotone cubic (PCHIP) through them
  double jitter_m = 0.0;          ///< RMS per axis of the hand tremor added to the intended path
  double jitter_min_hz = 4.0;
  double jitter_max_hz = 9.0;
  double palm_yaw_deg = 0.0;      ///< palm normal turned about y (0 = facing the sensor)
  double palm_pitch_deg = 0.0;    ///< about x
  double palm_roll_deg = 0.0;     ///< fingers turned about the view axis (0 = fingers up)
  bool distractor = true;         ///< the static box nearer than the hand
  double distractor_from_s = 0.0; ///< the box appears at this time (put down mid-take)
  double noise_raw = 0.35;        ///< sigma of disparity noise, raw units
  double edge_dropout = 0.35;     ///< chance that a pixel on a depth edge has no reading
  double dropout_blobs = 6.0;     ///< mean number of small no-reading blobs per frame
  int invalid_left_columns = 8;   ///< the band without readings at the left edge
  bool fingers_together = false;  ///< fingers side by side, touching (default: spread)
  bool second_person = false;     ///< a second person walks behind the user, left to right
  double second_person_z = 2.2;   ///< their torso's depth, metres
  // The randomized world (random_scene.hpp) sets these; the defaults are the bundled scenes' world.
  bool second_person_standing = false;  ///< the second person stands at second_person_x instead of walking
  double second_person_x = 0.0;
  double wall_z = 2.8;                  ///< the back wall's depth, metres
  Eigen::Vector3d user_offset = Eigen::Vector3d::Zero();  ///< the user moved by this (y: height, negative = taller; z: distance)
  bool left_handed = false;             ///< the active arm is the user's left (camera right)
  double arm_scale = 1.0;               ///< upper arm and forearm lengths times this
  std::vector<SceneObject> objects;     ///< furniture besides the `distractor` box
  /// Per-pixel noise from a hash of (seed, frame, pixel) instead of the sequential generator: the
  /// same noise level at a fifth of the cost (the generator was half the render time). The bundled
  /// scenes keep the sequence they were rendered with.
  bool hashed_noise = false;
  /// Where the hand rests (`"resting"` in a spec): false ("floating", the bundled scenes' world),
  /// 0.72 m below the shoulder, fingers up, facing the sensor: beyond the arm's reach, so a resting
  /// hand floats ~20 cm below the arm's end. True ("hanging", the randomized world): at the end of a
  /// relaxed arm (2 mm short of its length, the elbow bent ~10 degrees), fingers down, the palm
  /// toward the thigh; the hand turns into that pose over the last 15 cm of its way down, and is
  /// never drawn detached from the arm (a target below the shoulder out of reach is not reached
  /// either).
  bool hanging_rest = false;
};

/// Reads a scenario spec (JSON, see recordings/README.md). Throws std::runtime_error naming the
/// file and the offending key.
ScenarioSpec load_scenario(const std::filesystem::path& file);

/// One ground-truth row: the palm centre (centre of the palm's camera-facing surface).
struct GroundTruth {
  std::uint64_t frame = 0;
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d palm = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  bool visible = false;  ///< lifted (>= 15 cm off its resting pose), the whole palm face inside the image, >= 90% unoccluded
  bool raised = false;   ///< the hand is off its resting pose (more than 5 cm from it)
  bool rising = false;   ///< raised but less than 15 cm: on its way up or down (whether to report it is left open)
  Eigen::Vector3d intended = Eigen::Vector3d::Zero();  ///< the path without tremor
};

/// Renders one scenario frame by frame (deterministic for a given spec and seed).
class SyntheticScene {
 public:
  explicit SyntheticScene(ScenarioSpec spec, DepthModel model = {});
  ~SyntheticScene();
  SyntheticScene(const SyntheticScene&) = delete;
  SyntheticScene& operator=(const SyntheticScene&) = delete;

  std::uint64_t frame_count() const noexcept;
  /// Renders frame `i` (frames must be rendered in order for the noise to be reproducible).
  DepthFrame render(std::uint64_t i, GroundTruth& truth);
  const ScenarioSpec& spec() const noexcept;
  /// Where the hand hangs at rest (camera frame): below the image for the bundled user.
  Eigen::Vector3d rest_palm() const;

 private:
  struct Impl;
  Impl* impl_;
};

/// CSV header of ground_truth.csv.
inline constexpr const char* kGroundTruthHeader = "frame,stamp_ns,x,y,z,u,v,visible,intended_x,intended_y,intended_z,raised";

/// Renders every frame of `spec` into a fakenect recording at `out_dir` (depth + accelerometer
/// entries) and writes out_dir/ground_truth.csv. Returns the number of frames.
std::uint64_t write_synthetic_recording(const ScenarioSpec& spec, const std::filesystem::path& out_dir);

}  // namespace tachi::sensor
