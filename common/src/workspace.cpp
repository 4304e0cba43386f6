#include "tachi/common/workspace.hpp"

#include "tachi/common/text_file.hpp"

#include <Eigen/LU>
#include <nlohmann/json.hpp>

#include <stdexcept>
#include <vector>

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

namespace {
template <class T>
T read(const nlohmann::json& section, const char* key) {
  try {
    return section.at(key).get<T>();
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("workspace.") + key + ": " + e.what());
  }
}
}  // namespace

WorkspaceMapping workspace_from_json(const nlohmann::json& section) {
  WorkspaceMapping m = default_mapping();
  if (section.contains("rotation")) {
    const auto rows = read<std::vector<std::vector<float>>>(section, "rotation");
    if (rows.size() != 3 || rows[0].size() != 3 || rows[1].size() != 3 || rows[2].size() != 3)
      throw std::invalid_argument("workspace.rotation must be a 3x3 array of rows");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m.rotation(r, c) = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
  }
  if (section.contains("translation_m")) {
    const auto t = read<std::vector<float>>(section, "translation_m");
    if (t.size() != 3) throw std::invalid_argument("workspace.translation_m must be [x, y, z]");
    m.translation_m = {t[0], t[1], t[2]};
  }
  if (section.contains("scale")) m.scale = read<float>(section, "scale");
  if (const auto why = validate(m)) throw std::invalid_argument("workspace: " + *why);
  return m;
}

WorkspaceMapping read_workspace_config(const std::filesystem::path& file) {
  try {
    const auto root = nlohmann::json::parse(read_text_file(file, "workspace config"));
    if (!root.is_object()) throw std::invalid_argument("the document must be a JSON object");
    if (!root.contains("workspace")) return default_mapping();
    if (!root.at("workspace").is_object()) throw std::invalid_argument("workspace must be an object");
    return workspace_from_json(root.at("workspace"));
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(file.string() + ": not valid JSON: " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(file.string() + ": " + e.what());
  }
}

}  // namespace tachi::common
