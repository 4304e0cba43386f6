// Workspace mapping: where the user's hand is on the virtual cloth. Shared (common/): the filter maps the hand
// with it and the simulator maps a recording's scene (--object-from-recording) with the same one.
// A similarity transform world = scale * (R * camera + t) from the sensor's camera frame
// (x right, y down, z forward, metres) to the cloth's world frame (cloth in z = 0, x right, y up,
// centred at the origin). The default is a mirror for a user facing the sensor (docs/filter.md).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <filesystem>

#include <optional>
#include <string>

namespace tachi::common {

struct WorkspaceMapping {
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();  ///< proper rotation (orthonormal, det +1)
  Eigen::Vector3f translation_m = Eigen::Vector3f::Zero();
  float scale = 1.0F;  ///< world metres per (rotated, translated) camera metre

  Eigen::Vector3f to_world(const Eigen::Vector3f& camera) const;
  Eigen::Vector3f to_camera(const Eigen::Vector3f& world) const;
};

/// The mirror mapping: the user faces the sensor, so their right is the camera's -x and their up is
/// the camera's -y; a 180-degree turn about z maps both onto world +x and +y, and a hand
/// `plane_distance_m` from the sensor lands on the cloth plane z = 0 (the user's side is world +z).
WorkspaceMapping default_mapping(float plane_distance_m = 1.0F);

/// Why a mapping is unusable, or nothing when it is valid (rotation orthonormal with det +1 within 1e-3,
/// scale finite and > 0, translation finite).
std::optional<std::string> validate(const WorkspaceMapping& mapping);

/// A config's "workspace" section (docs/filter.md: "rotation" 3x3 rows, "translation_m" [x, y, z], "scale"), each
/// missing key keeping the default mapping's value. Throws std::invalid_argument naming the key ("workspace.scale:
/// ...") on a bad value, or saying why the mapping is unusable.
WorkspaceMapping workspace_from_json(const nlohmann::json& section);

/// The workspace of a tachi-filter config file (its "workspace" section; the default mapping without one), so
/// another stage maps the camera exactly as the filter does. Throws std::invalid_argument naming the file.
WorkspaceMapping read_workspace_config(const std::filesystem::path& file);

}  // namespace tachi::common
