// The pipeline's topics: one name and one QoS profile per message type of tachi.idl, and the one
// registry of them (for_each_topic) that the launcher, the recorder and the bus tools all read, so a
// topic added here is known to `tachi echo|hz|bw|record|play` without another list to keep.
#pragma once

#include "tachi.h"
#include "tachi/bus/bus.hpp"

#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace tachi::bus {

#define TACHI_BUS_DESCRIPTOR(type)                                          \
  template <>                                                               \
  struct Descriptor<type> {                                                 \
    static const dds_topic_descriptor_t& value() { return type##_desc; }    \
  }
TACHI_BUS_DESCRIPTOR(tachi_msg_RawHandSample);
TACHI_BUS_DESCRIPTOR(tachi_msg_VoiceCommand);
TACHI_BUS_DESCRIPTOR(tachi_msg_StrokeSample);
TACHI_BUS_DESCRIPTOR(tachi_msg_ClothTopology);
TACHI_BUS_DESCRIPTOR(tachi_msg_ClothTopologyDelta);
TACHI_BUS_DESCRIPTOR(tachi_msg_ClothState);
TACHI_BUS_DESCRIPTOR(tachi_msg_CutEvent);
TACHI_BUS_DESCRIPTOR(tachi_msg_NodeStatus);
TACHI_BUS_DESCRIPTOR(tachi_msg_SceneObject);
#undef TACHI_BUS_DESCRIPTOR

namespace topics {
inline constexpr TopicSpec<tachi_msg_RawHandSample> raw_hand{"tachi/hand/raw", QosProfile::SensorData};
inline constexpr TopicSpec<tachi_msg_VoiceCommand> voice_command{"tachi/voice/command", QosProfile::Commands};
inline constexpr TopicSpec<tachi_msg_StrokeSample> stroke{"tachi/hand/stroke", QosProfile::Strokes};
inline constexpr TopicSpec<tachi_msg_ClothTopology> cloth_topology{"tachi/cloth/topology", QosProfile::Topology};
/// The deltas: reliable and volatile, 1024 kept for a slow reader; a late joiner starts from the keyframe above.
inline constexpr TopicSpec<tachi_msg_ClothTopologyDelta> cloth_topology_delta{"tachi/cloth/topology_delta",
                                                                                QosProfile::Commands};
inline constexpr TopicSpec<tachi_msg_ClothState> cloth_state{"tachi/cloth/state", QosProfile::State};
/// The largest grid tachi-sim simulates live (per side; --offline goes to 4096): a 512 x 512 state is
/// 3 MB at every published step, already more than a frame's time on this bus, and it bounds what
/// a reader takes as a state: the particles of that grid cut up to twice over, xyz each (1.57 M floats).
inline constexpr int kMaxLiveGrid = 512;
inline constexpr std::size_t kMaxClothStateFloats = std::size_t{3} * kMaxLiveGrid * kMaxLiveGrid * 2;
inline constexpr TopicSpec<tachi_msg_CutEvent> cut_event{"tachi/cloth/cut", QosProfile::Commands};
inline constexpr TopicSpec<tachi_msg_NodeStatus> node_status{"tachi/node/status", QosProfile::Status};
/// Transient-local like the topology: a late viewer still gets the object.
inline constexpr TopicSpec<tachi_msg_SceneObject> scene_object{"tachi/scene/object", QosProfile::Topology};
}  // namespace topics

/// Calls `f(spec)` with every topic's TopicSpec, in pipeline order. The one list of tachi's topics.
template <class F>
void for_each_topic(F&& f) {
  f(topics::raw_hand);
  f(topics::voice_command);
  f(topics::stroke);
  f(topics::cloth_topology);
  f(topics::cloth_topology_delta);
  f(topics::cloth_state);
  f(topics::cut_event);
  f(topics::node_status);
  f(topics::scene_object);
}

/// A topic without its C++ type: what a tool that handles every topic alike (record, play, hz, bw) needs.
struct TopicInfo {
  const char* name;
  QosProfile profile;
  const dds_topic_descriptor_t* descriptor;  ///< the idlc type: its name, size and (de)serialization ops
  [[nodiscard]] std::string_view type_name() const { return descriptor->m_typename; }
};

/// Every topic of for_each_topic, untyped.
inline const std::vector<TopicInfo>& all_topics() {
  static const std::vector<TopicInfo> all = [] {
    std::vector<TopicInfo> v;
    for_each_topic([&](const auto& spec) {
      using T = typename std::remove_cvref_t<decltype(spec)>::Type;
      v.push_back({spec.name, spec.profile, &Descriptor<T>::value()});
    });
    return v;
  }();
  return all;
}

/// The topic named `name`, or nullptr.
inline const TopicInfo* find_topic(std::string_view name) {
  for (const auto& t : all_topics())
    if (name == t.name) return &t;
  return nullptr;
}

/// Calls `f(spec)` with the typed TopicSpec of the topic named `name`; false when there is none.
template <class F>
bool visit_topic(std::string_view name, F&& f) {
  bool found = false;
  for_each_topic([&](const auto& spec) {
    if (!found && name == spec.name) {
      found = true;
      f(spec);
    }
  });
  return found;
}

/// The names of every topic, comma separated (for error messages and --help).
inline std::string topic_names() {
  std::string names;
  for (const auto& t : all_topics()) names += (names.empty() ? "" : ", ") + std::string(t.name);
  return names;
}

}  // namespace tachi::bus
