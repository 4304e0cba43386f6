#include "tachi/bus/bus.hpp"
#include "tachi/bus/run_partition.hpp"

#include "tachi/common/process.hpp"
#include "tachi/common/text_file.hpp"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>
#include <random>
#include <thread>

namespace tachi::bus {
namespace {

// USER_DATA of an observer's reader (ReaderKind::Observer).
constexpr std::string_view kObserverMark = "tachi.observer";

// lossy_config_xml's retransmission timing (measured: docs/reliability.md, "Lossy links").
constexpr const char* kLossyLinkTimingXml =
    "<NackDelay>0 ms</NackDelay>"
    "<HeartbeatInterval min=\"2 ms\" minsched=\"5 ms\" max=\"100 ms\">10 ms</HeartbeatInterval>";
constexpr const char* kLossyLinkDiscoveryInterval = "500 ms";

// Cyclone allows one explicitly created domain per id per process, and deleting it deletes every
// participant in it; so domains are shared and reference counted between Participants.
struct DomainEntry {
  dds_entity_t domain = 0;
  int users = 0;
};
std::mutex g_domains_mutex;
std::map<std::uint32_t, DomainEntry> g_domains;

// Cyclone reads an empty config string as "use the defaults", which multicast on every interface,
// and one that does not start with '<' as a file name: both are errors here, naming the file.
std::string read_dds_config(const std::string& path) {
  std::string xml = common::read_text_file(path, "DDS config file");
  const auto first = xml.find_first_not_of(" \t\r\n");
  if (first == std::string::npos)
    throw std::runtime_error("DDS config file " + path + " is empty (refusing Cyclone's network defaults)");
  if (xml[first] != '<') throw std::runtime_error("DDS config file " + path + " is not XML (expected <CycloneDDS>)");
  return xml;
}

// Security's files, checked before Cyclone sees them so the error names the file (Cyclone's own says
// only "Not allowed by security" or "Error"), then given as the participant's dds.sec.* properties.
std::string security_file(const Security& security, const std::string& name) {
  std::error_code ec;
  const auto path = std::filesystem::absolute(std::filesystem::path(security.dir) / name, ec);
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw std::runtime_error("--secure " + security.dir + ": " + path.string() + " " +
                             (std::filesystem::exists(path, ec) ? "is not a file" : "does not exist") +
                             " (make the directory with scripts/make_test_pki.sh)");
  }
  return "file:" + path.string();
}

void set_security_properties(dds_qos_t* qos, const Security& security) {
  if (security.identity.empty()) throw std::runtime_error("--secure " + security.dir + ": no identity given");
  const struct {
    const char* name;
    std::string value;
  } properties[] = {
      {"dds.sec.auth.library.path", "dds_security_auth"},
      {"dds.sec.auth.library.init", "init_authentication"},
      {"dds.sec.auth.library.finalize", "finalize_authentication"},
      {"dds.sec.crypto.library.path", "dds_security_crypto"},
      {"dds.sec.crypto.library.init", "init_crypto"},
      {"dds.sec.crypto.library.finalize", "finalize_crypto"},
      {"dds.sec.access.library.path", "dds_security_ac"},
      {"dds.sec.access.library.init", "init_access_control"},
      {"dds.sec.access.library.finalize", "finalize_access_control"},
      {"dds.sec.auth.identity_ca", security_file(security, "identity_ca.pem")},
      {"dds.sec.auth.identity_certificate", security_file(security, security.identity + ".cert.pem")},
      {"dds.sec.auth.private_key", security_file(security, security.identity + ".key.pem")},
      {"dds.sec.access.permissions_ca", security_file(security, "permissions_ca.pem")},
      {"dds.sec.access.governance", security_file(security, "governance.p7s")},
      {"dds.sec.access.permissions", security_file(security, "permissions.p7s")},
  };
  for (const auto& p : properties) dds_qset_prop(qos, p.name, p.value.c_str());
}

// A participant created in a domain that was not explicitly created gets Cyclone's default
// config, which multicasts on every interface. So the domain entry is recorded only after
// dds_create_domain succeeded, and any failure leaves no entry behind.
void acquire_domain(std::uint32_t id, const std::string& config_file) {
  std::lock_guard lock(g_domains_mutex);
  if (const auto it = g_domains.find(id); it != g_domains.end()) {
    ++it->second.users;
    return;
  }
  const std::string xml = dds_config_xml(config_file);
  const dds_entity_t domain = check(
      dds_create_domain(id, xml.c_str()),
      "create DDS domain " + std::to_string(id) + (config_file.empty() ? "" : " from " + config_file) + ": dds_create_domain");
  g_domains.emplace(id, DomainEntry{domain, 1});
}

void release_domain(std::uint32_t id) noexcept {
  std::lock_guard lock(g_domains_mutex);
  const auto it = g_domains.find(id);
  if (it == g_domains.end()) return;
  if (--it->second.users == 0) {
    dds_delete(it->second.domain);
    g_domains.erase(it);
  }
}

std::atomic<bool> g_read_every_run{false};

using QosPtr = std::unique_ptr<dds_qos_t, decltype(&dds_delete_qos)>;

// Transient-local, keeping the newest `depth` samples per instance for readers that join late. Both
// depths: Cyclone 0.10.2's writer history (dds_whc.c) serves late joiners from durability_service's
// history, whose default depth is 1, and prunes to it every sample all current readers have acknowledged;
// history alone only bounds what is kept until then. With history alone a simulator that matched the
// filter late received one stroke sample of all those written before it, whenever another reader (a
// viewer, a recorder, the launcher's observer) had taken them already.
void keep_for_late_joiners(dds_qos_t* qos, std::int32_t depth) {
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, depth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                              DDS_LENGTH_UNLIMITED);
}

QosPtr make_qos(QosProfile profile) {
  QosPtr qos(dds_create_qos(), &dds_delete_qos);
  switch (profile) {
    case QosProfile::SensorData:
      // Keep-last, so a slow reader never blocks the camera; reliable and transient-local, so a filter
      // restarted mid-stroke receives the hand samples published while it was down and its journal
      // (tachi-filter --journal) carries the stroke on without a gap. Loopback loses nothing, so being
      // reliable costs no latency here; on a lossy link keep-last still bounds what is resent.
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
      keep_for_late_joiners(qos.get(), 64);
      break;
    case QosProfile::Commands:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1024);
      break;
    case QosProfile::Strokes:
      // The writer keeps its last 256 samples (~8.5 s of hand at 30 Hz) for readers that join late: a
      // simulator restarted after a crash catches up on what was published while it was down (its
      // journal holds the rest), and the launcher restarts it within 4 s backoff + ~2 s start. Each kept
      // sample is allocated at its size (~100 bytes: idl/src/writer_sertype.cpp), ~26 KB in all.
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
      keep_for_late_joiners(qos.get(), 256);
      break;
    case QosProfile::Topology:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
      keep_for_late_joiners(qos.get(), 1);
      break;
    case QosProfile::State:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 2);
      break;
    case QosProfile::Status:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
      keep_for_late_joiners(qos.get(), 1);
      dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, DDS_SECS(3));
      break;
  }
  return qos;
}

}  // namespace

std::string dds_config_xml(const std::string& config_file) {
  return config_file.empty() ? std::string(kLoopbackConfigXml) : read_dds_config(config_file);
}

std::string lossy_config_xml(const std::string& base_xml, int permille) {
  if (permille < 0 || permille > kMaxTransmitLossPermille)
    throw std::invalid_argument("transmit loss must be 0-" + std::to_string(kMaxTransmitLossPermille) + " per mille, not " +
                                std::to_string(permille));
  // Cyclone's defaults answer a loss late: a reader NACKs 100 ms after the heartbeat that shows the
  // gap (NackDelay), and a writer heartbeats every 100 ms (HeartbeatInterval), so one lost hand
  // sample waited ~100-200 ms. A link that loses packets wants the answer at once; the heartbeats
  // are sent only while data is unacknowledged, so the extra traffic stops when nothing is lost.
  //
  // Participant discovery is best effort and Cyclone repeats it every 30 s (SPDPInterval): a process that
  // joins a running pipeline and loses its one announcement to a peer is unknown to that peer for 30 s.
  // A sensor that plays a recording lives ~3 s, so 1 run in ~6 ended with the launcher never having
  // heard its heartbeat (summary frames 0). Announcing every 500 ms costs a few packets a second.
  return base_xml + "\n<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain id=\"any\">" +
         "<Discovery><SPDPInterval>" + std::string(kLossyLinkDiscoveryInterval) + "</SPDPInterval></Discovery><Internal>" +
         "<Test><XmitLossiness>" + std::to_string(permille) + "</XmitLossiness></Test>" +
         std::string(kLossyLinkTimingXml) + "</Internal></Domain></CycloneDDS>\n";
}

DdsError::DdsError(std::string_view context, dds_return_t code)
    : std::runtime_error(std::string(context) + ": " + dds_strretcode(code)), code_(code) {}

std::string run_partition() {
  static const std::string partition = [] {
    const char* id = std::getenv(kRunIdEnv);
    return id != nullptr && *id != '\0' ? std::string("tachi.run.") + id : std::string();
  }();
  return partition;
}

void read_every_run() { g_read_every_run = true; }

dds_return_t check(dds_return_t rc, std::string_view context) {
  if (rc < 0) throw DdsError(context, rc);
  return rc;
}

void throw_on_topic(dds_return_t rc, std::string_view action, std::string_view topic, std::string_view call) {
  throw DdsError(std::string(action).append(" on topic ").append(topic).append(": ").append(call), rc);
}

std::uint64_t new_session_id() {
  std::random_device entropy;
  std::uint64_t id = 0;
  while (id == 0) id = (static_cast<std::uint64_t>(entropy()) << 32) ^ entropy();
  return id;
}

Participant::Participant(std::uint32_t domain, const std::string& config_file, const Security& security)
    : domain_(domain) {
  QosPtr qos(dds_create_qos(), &dds_delete_qos);
  if (security.enabled()) set_security_properties(qos.get(), security);
  acquire_domain(domain, config_file);
  participant_ = dds_create_participant(domain, qos.get(), nullptr);
  if (participant_ < 0) {
    release_domain(domain);
    check(participant_, "create participant in domain " + std::to_string(domain) +
                            (security.enabled() ? " with identity " + security.identity + " of " + security.dir : "") +
                            ": dds_create_participant");
  }
}

Participant::~Participant() {
  dds_delete(participant_);
  release_domain(domain_);
}

namespace detail {

// The sensor asks every frame whether its filter is there: the matched readers are listed (an allocation
// and a discovery lookup each) only when the writer's publication-matched status moved since the last
// answer. A match raises total_count and an unmatch lowers current_count, so any change moves the pair.
struct ConsumerCount {
  std::uint32_t total = 0, current = 0, consumers = 0;
};
std::mutex g_consumer_counts_mutex;
std::map<dds_entity_t, ConsumerCount> g_consumer_counts;  // by writer; erased in delete_entity

std::uint32_t count_consumers(dds_entity_t writer);

dds_entity_t create_topic(const Participant& participant, const dds_topic_descriptor_t* descriptor,
                          const char* name) {
  return check(dds_create_topic(participant.handle(), descriptor, name, nullptr, nullptr),
               std::string("create topic ") + name + ": dds_create_topic");
}

dds_entity_t create_writer(const Participant& participant, dds_entity_t topic, QosProfile profile,
                           const char* name) {
  const auto qos = make_qos(profile);
  if (const auto partition = run_partition(); !partition.empty()) dds_qset_partition1(qos.get(), partition.c_str());
  return check(dds_create_writer(participant.handle(), topic, qos.get(), nullptr),
               std::string("create writer on topic ") + name + ": dds_create_writer");
}

dds_entity_t create_reader(const Participant& participant, dds_entity_t topic, QosProfile profile,
                           const char* name, ReaderQos change, ReaderKind kind) {
  const auto qos = make_qos(profile);
  if (kind == ReaderKind::Observer) dds_qset_userdata(qos.get(), kObserverMark.data(), kObserverMark.size());
  if (change == ReaderQos::KeepAll) dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  if (change == ReaderQos::Volatile) dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  if (g_read_every_run) dds_qset_partition1(qos.get(), "*");
  else if (const auto partition = run_partition(); !partition.empty()) dds_qset_partition1(qos.get(), partition.c_str());
  return check(dds_create_reader(participant.handle(), topic, qos.get(), nullptr),
               std::string("create reader on topic ") + name + ": dds_create_reader");
}

void delete_entity(dds_entity_t entity) noexcept {
  {
    std::lock_guard lock(g_consumer_counts_mutex);
    g_consumer_counts.erase(entity);
  }
  dds_delete(entity);
}


std::uint32_t matched_consumers(dds_entity_t writer) {
  dds_publication_matched_status_t status{};
  check(dds_get_publication_matched_status(writer, &status), "dds_get_publication_matched_status");
  {
    std::lock_guard lock(g_consumer_counts_mutex);
    const auto it = g_consumer_counts.find(writer);
    if (it != g_consumer_counts.end() && it->second.total == status.total_count && it->second.current == status.current_count)
      return it->second.consumers;
  }
  const std::uint32_t consumers = status.current_count == 0 ? 0 : count_consumers(writer);
  std::lock_guard lock(g_consumer_counts_mutex);
  g_consumer_counts[writer] = {status.total_count, status.current_count, consumers};
  return consumers;
}

std::uint32_t count_consumers(dds_entity_t writer) {
  std::vector<dds_instance_handle_t> readers(8);
  dds_return_t n = 0;
  while ((n = check(dds_get_matched_subscriptions(writer, readers.data(), readers.size()), "dds_get_matched_subscriptions")) >
         static_cast<dds_return_t>(readers.size()))
    readers.resize(static_cast<std::size_t>(n));
  std::uint32_t consumers = 0;
  for (dds_return_t i = 0; i < n; ++i) {
    dds_builtintopic_endpoint_t* reader = dds_get_matched_subscription_data(writer, readers[static_cast<std::size_t>(i)]);
    if (reader == nullptr) continue;  // unmatched meanwhile
    void* mark = nullptr;
    std::size_t size = 0;
    const bool observer = reader->qos != nullptr && dds_qget_userdata(reader->qos, &mark, &size) && size == kObserverMark.size() &&
                          std::memcmp(mark, kObserverMark.data(), size) == 0;
    dds_free(mark);
    dds_builtintopic_free_endpoint(reader);
    if (!observer) ++consumers;
  }
  return consumers;
}

std::uint32_t matched_writers(dds_entity_t reader) {
  dds_subscription_matched_status_t status{};
  check(dds_get_subscription_matched_status(reader, &status), "dds_get_subscription_matched_status");
  return status.current_count;
}

bool wait_until_count(const std::function<std::uint32_t()>& count, std::uint32_t n,
                      std::chrono::nanoseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  // A stop request (SIGINT/SIGTERM) ends the wait too: a process waiting for a peer must still stop.
  while (count() < n) {
    if (std::chrono::steady_clock::now() >= deadline || common::stop_requested()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

bool wait_for_data(dds_entity_t reader, std::chrono::nanoseconds timeout) {
  const dds_entity_t waitset = check(dds_create_waitset(dds_get_participant(reader)), "dds_create_waitset");
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_return_t rc = condition;
  if (condition >= 0) rc = dds_waitset_attach(waitset, condition, condition);
  if (rc >= 0) rc = dds_waitset_wait(waitset, nullptr, 0, timeout.count());
  if (condition >= 0) dds_delete(condition);
  dds_delete(waitset);
  return check(rc, "wait for data: dds_waitset_wait") > 0;
}

bool wait_for_acks(dds_entity_t writer, std::chrono::nanoseconds timeout) {
  const dds_return_t rc = dds_wait_for_acks(writer, timeout.count());
  if (rc == DDS_RETCODE_TIMEOUT) return false;
  check(rc, "wait for acknowledgements: dds_wait_for_acks");
  return true;
}

}  // namespace detail

WaitSet::WaitSet(const Participant& participant)
    : waitset_(check(dds_create_waitset(participant.handle()), "create waitset: dds_create_waitset")) {}

WaitSet::~WaitSet() {
  for (const auto condition : conditions_) dds_delete(condition);
  dds_delete(waitset_);
}

void WaitSet::attach_reader(dds_entity_t reader) {
  const dds_entity_t condition =
      check(dds_create_readcondition(reader, DDS_ANY_STATE), "attach reader to waitset: dds_create_readcondition");
  conditions_.push_back(condition);
  check(dds_waitset_attach(waitset_, condition, condition), "attach reader to waitset: dds_waitset_attach");
}

bool WaitSet::wait(std::chrono::nanoseconds timeout) {
  return check(dds_waitset_wait(waitset_, nullptr, 0, timeout.count()), "wait: dds_waitset_wait") > 0;
}

}  // namespace tachi::bus
