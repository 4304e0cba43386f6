#include "tachi/common/workspace.hpp"

#include <Eigen/LU>

#include <cmath>

namespace tachi::common {

Eigen::Vector3f WorkspaceMapping::to_world(const Eigen::Vector3f& camera) const {
  return scale * (rotation * camera + translation_m);
}

Eigen::Vector3f WorkspaceMapping::to_camera(const Eigen::Vector3f& world) const {
  return rotation.transpose() * (world / scale - translation_m);
}

WorkspaceMapping default_mapping(float plane_distance_m) {
  WorkspaceMapping m;
  // Camera -x (the user's right) -> world +x; camera -y (up) -> world +y; camera z -> world z.
  m.rotation = Eigen::Vector3f{-1.0F, -1.0F, 1.0F}.asDiagonal();
  m.translation_m = {0.0F, 0.0F, -plane_distance_m};
  m.scale = 1.0F;
  return m;
}

std::optional<std::string> validate(const WorkspaceMapping& mapping) {
  if (!mapping.rotation.allFinite() || !mapping.translation_m.allFinite()) return "rotation and translation must be finite";
  if (!std::isfinite(mapping.scale) || mapping.scale <= 0.0F) return "scale must be finite and > 0";
  const Eigen::Matrix3f gram = mapping.rotation.transpose() * mapping.rotation;
  if (!gram.isApprox(Eigen::Matrix3f::Identity(), 1e-3F)) return "rotation must be orthonormal (R^T R = I)";
  if (std::abs(mapping.rotation.determinant() - 1.0F) > 1e-3F)
    return "rotation must be proper (det +1): a reflection would turn the cloth inside out";
  return std::nullopt;
}

}  // namespace tachi::common
