// Objects to drape the cloth over (seed 000 section 2: "the object model is given as a point cloud").
// Two sources: a PLY file (ascii or binary, read with assimp, Debian's libassimp-dev, rather than a reader
// of our own) placed by a pose, and the static scene of a Kinect recording's first depth frames (the
// sensor library's fakenect reader and depth model; the filter's camera-to-world mapping). The points
// become a PointCloudCollider (collision.hpp). Lives in tachi_sim_object so tachi_sim stays free of
// assimp and the sensor library.
#pragma once

#include "tachi/common/workspace.hpp"
#include "tachi/sim/collision.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tachi::sim {

/// Where an object sits in the cloth's world frame (x right, y up, cloth in z = 0): p_world = t + R (s p),
/// R = Rz(rz) Ry(ry) Rx(rx), angles in degrees.
struct ObjectPose {
  Eigen::Vector3f translation_m = Eigen::Vector3f::Zero();
  Eigen::Vector3f rotation_deg = Eigen::Vector3f::Zero();
  float scale = 1.0F;
  [[nodiscard]] Eigen::Affine3f transform() const;
};

/// "X,Y,Z" or "X,Y,Z,RX,RY,RZ" or "X,Y,Z,RX,RY,RZ,S" (metres, degrees, scale > 0), all finite; nothing otherwise.
[[nodiscard]] std::optional<ObjectPose> parse_object_pose(const std::string& text);

/// The vertices of a PLY file (ascii or binary; faces, if any, are ignored: the object is its points).
/// Throws std::runtime_error naming the file when it cannot be read or holds no finite vertex.
[[nodiscard]] std::vector<Eigen::Vector3f> load_ply_points(const std::filesystem::path& file);

/// The static scene of a fakenect recording in the world frame: per pixel the median of the first
/// `frames` depth frames (pixels without a reading in most of them are dropped), every `stride`-th
/// pixel back-projected with the recording's depth model and mapped to the world with `workspace`: the
/// filter's mapping, so the scene lands where the recorded hand does. Throws std::runtime_error naming the
/// recording on a bad one.
[[nodiscard]] std::vector<Eigen::Vector3f> scene_from_recording(const std::filesystem::path& dir,
                                                               const common::WorkspaceMapping& workspace,
                                                               int frames = 5, int stride = 4);

/// What --object, --object-pose, --object-from-recording ask for.
struct ObjectOptions {
  std::filesystem::path file;
  ObjectPose pose;
  std::filesystem::path recording;
  common::WorkspaceMapping workspace = common::default_mapping();  ///< camera -> world for the recording (the filter's)
  float influence_m = 0.03F;     ///< repulsion reaches this far from an object point
  float stiffness = 300.0F;      ///< repulsive acceleration at zero distance, m/s^2
};

/// The collider the options ask for, or null when they ask for none. Throws naming the file.
[[nodiscard]] std::shared_ptr<const PointCloudCollider> load_object(const ObjectOptions& options);

}  // namespace tachi::sim
