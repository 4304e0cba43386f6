// What is on a domain, from Cyclone's built-in discovery topics (DCPSParticipant, DCPSPublication,
// DCPSSubscription): the participants with their process, host and pid (Cyclone announces them as
// the participant properties __ProcessName, __Hostname, __Pid), and every writer and reader with its
// topic and type. Backs `tachi topics`; works for any DDS application on the domain, not only tachi's.
#pragma once

#include "tachi/bus/bus.hpp"

#include <chrono>
#include <string>
#include <vector>

namespace tachi::bus {

struct ParticipantInfo {
  std::string key;      ///< GUID, hex
  std::string process;  ///< empty when the participant did not announce it
  std::string host;
  std::string pid;
  bool self = false;    ///< the participant doing the discovery
};

struct EndpointInfo {
  std::string participant_key;
  std::string topic;
  std::string type;
  bool writer = false;
  std::string qos;  ///< e.g. "reliable, transient-local, keep-last 64, liveliness automatic 3 s" (`tachi topics --verbose`)
};

/// The QoS a writer offers or a reader requests, in words: reliability, durability, history, and
/// deadline, liveliness and partitions when they are not the defaults.
std::string describe_qos(const dds_qos_t* qos);

struct DomainSnapshot {
  std::vector<ParticipantInfo> participants;
  std::vector<EndpointInfo> endpoints;
};

/// Joins `participant`'s domain's discovery for `listen` (discovery takes a moment), then reports
/// everything seen and still alive.
DomainSnapshot discover(const Participant& participant, std::chrono::milliseconds listen);

}  // namespace tachi::bus
