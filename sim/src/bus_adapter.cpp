#include "bus_adapter.hpp"

#include <algorithm>
#include <cmath>

namespace tachi::sim {

tachi_msg_Blade to_msg(Blade blade) {
  switch (blade) {
    case Blade::Razor: return tachi_msg_BLADE_RAZOR;
    case Blade::Scalpel: return tachi_msg_BLADE_SCALPEL;
    case Blade::Utility: return tachi_msg_BLADE_UTILITY;
    case Blade::Kitchen: return tachi_msg_BLADE_KITCHEN;
    case Blade::Hunting: return tachi_msg_BLADE_HUNTING;
    case Blade::Worn: return tachi_msg_BLADE_WORN;
  }
  return tachi_msg_BLADE_SCALPEL;  // unreachable: every Blade is listed
}
namespace {
template <class Seq, class T>
void point_at(Seq& seq, std::vector<T>& data) {
  seq._buffer = data.data();
  seq._length = seq._maximum = static_cast<std::uint32_t>(data.size());
  seq._release = false;
}
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions are sent as packed xyz floats");
constexpr float kFarFromAnyCloth_m = 100.0f;
}  // namespace

std::optional<StrokeInput> from_msg(const tachi_msg_StrokeSample& msg) {
  const Eigen::Vector3f p(msg.position_m.x, msg.position_m.y, msg.position_m.z);
  if (msg.tracked && (!p.allFinite() || p.cwiseAbs().maxCoeff() > kFarFromAnyCloth_m)) return std::nullopt;
  StrokeInput input;
  input.sensor_id = msg.sensor_id;
  input.session_id = msg.session_id;
  input.stroke_id = msg.stroke_id;
  input.time_s = static_cast<double>(msg.time_ns) * 1e-9;
  input.position_m = p;
  input.tracked = msg.tracked;
  input.cutting = msg.gate == tachi_msg_GATE_CUTTING;
  input.holding = msg.gate == tachi_msg_GATE_HOLDING;
  input.grabbing = msg.gate == tachi_msg_GATE_GRABBING;
  return input;
}

void TopologyMessage::fill(std::uint32_t cloth_id, const Cloth& cloth, const TopologyChange* change,
                           std::uint64_t session_id) {
  triangles_.clear();
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t)
    if (cloth.triangle_alive[t]) triangles_.insert(triangles_.end(), cloth.triangles[t].begin(), cloth.triangles[t].end());
  grid_.resize(cloth.particle_count());
  for (std::size_t i = 0; i < grid_.size(); ++i)
    grid_[i] = {static_cast<std::uint16_t>(cloth.grid[i].u), static_cast<std::uint16_t>(cloth.grid[i].v)};
  pinned_.assign(cloth.pinned.begin(), cloth.pinned.end());
  duplicated_from_.clear();
  changed_triangles_.clear();
  if (change != nullptr) {
    duplicated_from_ = change->duplicated_from;
    changed_triangles_ = change->changed_triangles;
  }
  msg_ = {};
  msg_.cloth_id = cloth_id;
  msg_.session_id = session_id;
  msg_.version = cloth.topology_version;
  msg_.base_version = published_version_.value_or(cloth.topology_version);
  published_version_ = cloth.topology_version;
  msg_.columns = static_cast<std::uint16_t>(cloth.columns);
  msg_.rows = static_cast<std::uint16_t>(cloth.rows);
  point_at(msg_.triangles, triangles_);
  point_at(msg_.particle_grid, grid_);
  msg_.pinned._buffer = reinterpret_cast<bool*>(pinned_.data());
  msg_.pinned._length = msg_.pinned._maximum = static_cast<std::uint32_t>(pinned_.size());
  msg_.pinned._release = false;
  point_at(msg_.duplicated_from, duplicated_from_);
  point_at(msg_.changed_triangles, changed_triangles_);
}

std::size_t TopologyMessage::payload_bytes() const {
  return sizeof(std::uint32_t) * (triangles_.size() + duplicated_from_.size() + changed_triangles_.size()) +
         sizeof(tachi_msg_GridCoord) * grid_.size() + pinned_.size();
}

TopologyDeltaMessage::TopologyDeltaMessage(const Cloth& cloth)
    : version_(cloth.topology_version),
      particles_(cloth.particle_count()),
      published_(cloth.triangles.begin(), cloth.triangles.end()),
      published_alive_(cloth.triangle_alive.begin(), cloth.triangle_alive.end()) {}

void TopologyDeltaMessage::fill(std::uint32_t cloth_id, const Cloth& cloth, const TopologyChange& change,
                                std::uint64_t session_id) {
  grid_.clear();
  pinned_.clear();
  for (std::size_t i = particles_; i < cloth.particle_count(); ++i) {
    grid_.push_back({static_cast<std::uint16_t>(cloth.grid[i].u), static_cast<std::uint16_t>(cloth.grid[i].v)});
    pinned_.push_back(cloth.pinned[i]);
  }
  removed_.clear();
  added_.clear();
  published_.resize(cloth.triangle_count(), {0, 0, 0});
  published_alive_.resize(cloth.triangle_count(), 0);
  for (const std::uint32_t t : change.changed_triangles) {
    if (t >= cloth.triangle_count()) continue;
    if (published_alive_[t] != 0) removed_.insert(removed_.end(), published_[t].begin(), published_[t].end());
    if (cloth.triangle_alive[t] != 0) added_.insert(added_.end(), cloth.triangles[t].begin(), cloth.triangles[t].end());
    published_[t] = cloth.triangles[t];
    published_alive_[t] = cloth.triangle_alive[t];
  }
  msg_ = {};
  msg_.cloth_id = cloth_id;
  msg_.session_id = session_id;
  msg_.base_version = version_;
  msg_.version = cloth.topology_version;
  version_ = cloth.topology_version;
  particles_ = cloth.particle_count();
  point_at(msg_.new_particle_grid, grid_);
  msg_.new_particle_pinned._buffer = reinterpret_cast<bool*>(pinned_.data());
  msg_.new_particle_pinned._length = msg_.new_particle_pinned._maximum = static_cast<std::uint32_t>(pinned_.size());
  msg_.new_particle_pinned._release = false;
  point_at(msg_.removed_triangles, removed_);
  point_at(msg_.added_triangles, added_);
  // The merged change lists every particle appended since the last delta, in order.
  duplicated_from_.assign(change.duplicated_from.end() - static_cast<std::ptrdiff_t>(std::min(change.duplicated_from.size(), grid_.size())),
                          change.duplicated_from.end());
  point_at(msg_.duplicated_from, duplicated_from_);
}

std::size_t TopologyDeltaMessage::payload_bytes() const {
  return sizeof(tachi_msg_GridCoord) * grid_.size() + pinned_.size() +
         sizeof(std::uint32_t) * (removed_.size() + added_.size() + duplicated_from_.size());
}

tachi_msg_ClothState state_msg(std::uint32_t cloth_id, std::uint64_t frame, double sim_time_s, const Cloth& cloth,
                               std::uint64_t session_id, std::optional<std::uint32_t> held) {
  tachi_msg_ClothState msg{};
  msg.cloth_id = cloth_id;
  msg.session_id = session_id;
  msg.frame = frame;
  msg.sim_time_ns = static_cast<std::int64_t>(std::llround(sim_time_s * 1e9));
  msg.topology_version = cloth.topology_version;
  // -1: nothing held (a zeroed message would say particle 0).
  msg.held_particle = held ? static_cast<std::int32_t>(*held) : -1;
  // The message is only read by dds_write; the cast drops const for the C struct's sake.
  msg.positions._buffer = const_cast<float*>(cloth.position.empty() ? nullptr : cloth.position.front().data());
  msg.positions._length = msg.positions._maximum = static_cast<std::uint32_t>(3 * cloth.particle_count());
  msg.positions._release = false;
  return msg;
}

const tachi_msg_SceneObject& ObjectMessage::fill(std::uint32_t cloth_id, const std::vector<Eigen::Vector3f>& points,
                                                 std::uint64_t session_id) {
  xyz_.clear();
  xyz_.reserve(3 * points.size());
  for (const Eigen::Vector3f& p : points) xyz_.insert(xyz_.end(), {p.x(), p.y(), p.z()});
  msg_ = {};
  msg_.cloth_id = cloth_id;
  msg_.session_id = session_id;
  point_at(msg_.points, xyz_);
  return msg_;
}

}  // namespace tachi::sim
