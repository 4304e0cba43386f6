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

std::string seconds(dds_duration_t d) {
  if (d == DDS_INFINITY) return "infinite";
  char text[32];
  std::snprintf(text, sizeof text, "%g s", static_cast<double>(d) * 1e-9);
  return text;
}

}  // namespace

std::string describe_qos(const dds_qos_t* qos) {
  if (qos == nullptr) return "?";
  std::string text;
  const auto add = [&](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
  dds_reliability_kind_t reliability{};
  dds_duration_t blocking = 0;
  if (dds_qget_reliability(qos, &reliability, &blocking)) add(reliability == DDS_RELIABILITY_RELIABLE ? "reliable" : "best-effort");
  dds_durability_kind_t durability{};
  if (dds_qget_durability(qos, &durability)) {
    static const char* const names[] = {"volatile", "transient-local", "transient", "persistent"};
    add(names[static_cast<int>(durability) & 3]);
  }
  dds_history_kind_t history{};
  int32_t depth = 0;
  if (dds_qget_history(qos, &history, &depth))
    add(history == DDS_HISTORY_KEEP_ALL ? std::string("keep-all") : "keep-last " + std::to_string(depth));
  dds_duration_t deadline = 0;
  if (dds_qget_deadline(qos, &deadline) && deadline != DDS_INFINITY) add("deadline " + seconds(deadline));
  dds_liveliness_kind_t liveliness{};
  dds_duration_t lease = 0;
  if (dds_qget_liveliness(qos, &liveliness, &lease) && lease != DDS_INFINITY)
    add(std::string("liveliness ") + (liveliness == DDS_LIVELINESS_AUTOMATIC ? "automatic " : "manual ") + seconds(lease));
  uint32_t n = 0;
  char** partitions = nullptr;
  if (dds_qget_partition(qos, &n, &partitions) && n > 0) {
    std::string names;
    for (uint32_t i = 0; i < n; ++i) {
      if (i > 0) names += ' ';
      names += partitions[i];
      dds_free(partitions[i]);
    }
    add("partition " + names);
  }
  dds_free(partitions);
  return text;
}

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
                                        e.type_name ? e.type_name : "", writer, describe_qos(e.qos)});
        });
  }
  return snapshot;
}

}  // namespace tachi::bus
