// The pipeline's topics: one name and one QoS profile per message type of tachi.idl.
#pragma once

#include "tachi.h"
#include "tachi/bus/bus.hpp"

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
/// Issue 11: reliable and volatile, 1024 kept for a slow reader; a late joiner starts from the keyframe above.
inline constexpr TopicSpec<tachi_msg_ClothTopologyDelta> cloth_topology_delta{"tachi/cloth/topology_delta",
                                                                                QosProfile::Commands};
inline constexpr TopicSpec<tachi_msg_ClothState> cloth_state{"tachi/cloth/state", QosProfile::State};
inline constexpr TopicSpec<tachi_msg_CutEvent> cut_event{"tachi/cloth/cut", QosProfile::Commands};
inline constexpr TopicSpec<tachi_msg_NodeStatus> node_status{"tachi/node/status", QosProfile::Status};
/// Transient-local like the topology: a late viewer still gets the object.
inline constexpr TopicSpec<tachi_msg_SceneObject> scene_object{"tachi/scene/object", QosProfile::Topology};
}  // namespace topics

}  // namespace tachi::bus
