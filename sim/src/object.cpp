#include "tachi/sim/object.hpp"

#include "tachi/sensor/depth_model.hpp"
#include "tachi/sensor/fakenect_recording.hpp"

#include <assimp/cimport.h>
#include <assimp/mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tachi::sim {

Eigen::Affine3f ObjectPose::transform() const {
  const float to_rad = std::numbers::pi_v<float> / 180.0F;
  Eigen::Affine3f t = Eigen::Affine3f::Identity();
  t.translate(translation_m);
  t.rotate(Eigen::AngleAxisf(rotation_deg.z() * to_rad, Eigen::Vector3f::UnitZ()) *
           Eigen::AngleAxisf(rotation_deg.y() * to_rad, Eigen::Vector3f::UnitY()) *
           Eigen::AngleAxisf(rotation_deg.x() * to_rad, Eigen::Vector3f::UnitX()));
  t.scale(scale);
  return t;
}

std::optional<ObjectPose> parse_object_pose(const std::string& text) {
  std::vector<float> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    float v = 0.0F;
    const char* first = text.data() + start;
    const char* last = text.data() + end;
    while (first < last && *first == ' ') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (ec != std::errc{} || ptr != last || !std::isfinite(v)) return std::nullopt;
    values.push_back(v);
    start = end + 1;
  }
  if (values.size() != 3 && values.size() != 6 && values.size() != 7) return std::nullopt;
  ObjectPose pose;
  pose.translation_m = {values[0], values[1], values[2]};
  if (values.size() >= 6) pose.rotation_deg = {values[3], values[4], values[5]};
  if (values.size() == 7) {
    if (!(values[6] > 0.0F)) return std::nullopt;
    pose.scale = values[6];
  }
  return pose;
}

std::vector<Eigen::Vector3f> load_ply_points(const std::filesystem::path& file) {
  // Assimp's PLY importer reads ascii and binary (both endians); a file with vertices and no faces
  // comes back as a mesh of points.
  const aiScene* scene = aiImportFile(file.c_str(), 0);
  if (scene == nullptr) throw std::runtime_error("cannot read the object " + file.string() + ": " + aiGetErrorString());
  std::vector<Eigen::Vector3f> points;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& v = mesh->mVertices[i];
      const Eigen::Vector3f p{v.x, v.y, v.z};
      if (p.allFinite()) points.push_back(p);
    }
  }
  aiReleaseImport(scene);
  if (points.empty()) throw std::runtime_error("the object " + file.string() + " has no finite vertex");
  return points;
}

std::vector<Eigen::Vector3f> scene_from_recording(const std::filesystem::path& dir, const common::WorkspaceMapping& mapping,
                                                  int frames, int stride) {
  std::vector<sensor::IndexEntry> depth;
  try {
    for (const auto& e : sensor::read_index(dir)) {
      if (e.kind == sensor::EntryKind::Depth) depth.push_back(e);
      if (static_cast<int>(depth.size()) == frames) break;
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string{"--object-from-recording: "} + e.what());
  }
  const sensor::DepthModel model = sensor::model_for_recording(dir);
  std::vector<std::vector<std::uint16_t>> raw(depth.size());
  for (std::size_t f = 0; f < depth.size(); ++f) sensor::read_depth_file(dir / depth[f].file, raw[f]);
  // The first frames show the scene without the hand (recordings/README.md): the per-pixel median
  // over them is the static scene, robust to a frame's noise.
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint16_t> values;
  for (int v = 0; v < sensor::kDepthHeight; v += stride) {
    for (int u = 0; u < sensor::kDepthWidth; u += stride) {
      const auto pixel = static_cast<std::size_t>(v * sensor::kDepthWidth + u);
      values.clear();
      for (const auto& frame : raw) {
        if (frame[pixel] < sensor::kNoReading) values.push_back(frame[pixel]);
      }
      if (values.size() * 2 <= raw.size()) continue;  // no reading in most frames
      std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
      const float z = model.metres(values[values.size() / 2]);
      if (!(z > 0.0F)) continue;
      const Eigen::Vector3d camera = model.back_project(u, v, z);
      points.push_back(mapping.to_world(camera.cast<float>()));
    }
  }
  if (points.empty()) throw std::runtime_error("--object-from-recording: " + dir.string() + " has no depth reading in its first frames");
  return points;
}

std::shared_ptr<const PointCloudCollider> load_object(const ObjectOptions& o) {
  std::vector<Eigen::Vector3f> points;
  if (!o.file.empty()) {
    const Eigen::Affine3f pose = o.pose.transform();
    for (const Eigen::Vector3f& p : load_ply_points(o.file)) points.push_back(pose * p);
  }
  if (!o.recording.empty()) {
    const auto scene = scene_from_recording(o.recording, o.workspace);
    points.insert(points.end(), scene.begin(), scene.end());
  }
  if (points.empty()) return nullptr;
  return std::make_shared<const PointCloudCollider>(std::move(points), o.influence_m, o.stiffness);
}

}  // namespace tachi::sim
