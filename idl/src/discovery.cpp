#include "tachi/bus/discovery.hpp"

#include <algorithm>
#include <cstdio>
#include <thread>

namespace tachi::bus {
namespace {

std::string guid_text(const dds_guid_t& guid) {
  std::string text;
  char byte[3];
  for (std::size_t i = 0; i < sizeof guid.v; ++i) {
    std::snprintf(byte, sizeof byte, "%02x", guid.v[i]);
    text += byte;
    if (i % 4 == 3 && i + 1 < sizeof guid.v) text += ':';
  }
  return text;
}

std::string property(const dds_qos_t* qos, const char* name) {
  char* value = nullptr;
  if (qos == nullptr || !dds_qget_prop(qos, name, &value) || value == nullptr) return {};
  std::string text(value);
  dds_free(value);
  return text;
}

// Reads every alive sample of a built-in topic; `each` gets the sample's pointer.
template <class Sample, class Each>
void read_builtin(dds_entity_t participant, dds_entity_t topic, Each each) {
  const dds_entity_t reader = check(dds_create_reader(participant, topic, nullptr, nullptr), "create built-in topic reader");
  constexpr std::size_t kMax = 256;
  void* samples[kMax] = {nullptr};
  dds_sample_info_t infos[kMax];
  const dds_return_t n = dds_read(reader, samples, infos, kMax, kMax);
  for (dds_return_t i = 0; i < n; ++i)
    if (infos[i].valid_data && infos[i].instance_state == DDS_IST_ALIVE) each(*static_cast<const Sample*>(samples[i]));
  if (n > 0) dds_return_loan(reader, samples, n);
  dds_delete(reader);
}

}  // namespace

DomainSnapshot discover(const Participant& participant, std::chrono::milliseconds listen) {
  // Built-in topic readers see what was discovered so far: give discovery its time first.
  std::this_thread::sleep_for(listen);
  const dds_entity_t pp = participant.handle();
  dds_guid_t own{};
  check(dds_get_guid(pp, &own), "dds_get_guid");
  DomainSnapshot snapshot;
  read_builtin<dds_builtintopic_participant_t>(pp, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, [&](const auto& p) {
    ParticipantInfo info;
    info.key = guid_text(p.key);
    info.process = property(p.qos, "__ProcessName");
    info.host = property(p.qos, "__Hostname");
    info.pid = property(p.qos, "__Pid");
    info.self = std::equal(std::begin(p.key.v), std::end(p.key.v), std::begin(own.v));
    snapshot.participants.push_back(std::move(info));
  });
  for (const bool writer : {true, false}) {
    read_builtin<dds_builtintopic_endpoint_t>(
        pp, writer ? DDS_BUILTIN_TOPIC_DCPSPUBLICATION : DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, [&](const auto& e) {
          snapshot.endpoints.push_back({guid_text(e.participant_key), e.topic_name ? e.topic_name : "",
                                        e.type_name ? e.type_name : "", writer});
        });
  }
  return snapshot;
}

}  // namespace tachi::bus
