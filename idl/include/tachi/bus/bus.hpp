// tachi's one typed layer over Cyclone DDS's C API: participant, typed writer and reader, waitset.
// Everything above this header speaks C++ (RAII handles, std::chrono, exceptions with context);
// everything below is Cyclone's C API. Message types are the idlc-generated C structs of tachi.idl.
#pragma once

#include <dds/dds.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tachi::bus {

/// config/cyclonedds-loopback.xml, embedded at build time: every byte stays on `lo`.
extern const char* const kLoopbackConfigXml;

/// The Cyclone config a Participant given `config_file` uses: the file's XML (throws naming the file
/// when it cannot be read, is empty or is not XML: never Cyclone's network defaults), or
/// kLoopbackConfigXml when `config_file` is empty.
std::string dds_config_xml(const std::string& config_file);

/// `base_xml` with Cyclone's transmit loss: each process drops `permille` of the packets it sends
/// (Internal/Test/XmitLossiness; data, heartbeats, acknowledgements and discovery alike), and the
/// reliable protocol's timing for such a link (a prompt NACK, frequent heartbeats while data is
/// unacknowledged; docs/reliability.md gives the measurement). Cyclone reads the two documents in
/// turn, the second's settings over the first's. Throws std::invalid_argument outside
/// 0-kMaxTransmitLossPermille.
std::string lossy_config_xml(const std::string& base_xml, int permille);
/// The most lossy_config_xml drops: 1000 would be no link at all.
inline constexpr int kMaxTransmitLossPermille = 999;

/// A Cyclone call failed. what() names the entity and the call, e.g.
/// "create writer on topic tachi/hand/raw: dds_create_writer: Precondition not met".
class DdsError : public std::runtime_error {
 public:
  DdsError(std::string_view context, dds_return_t code);
  dds_return_t code() const noexcept { return code_; }

 private:
  dds_return_t code_;
};

/// Returns `rc` when it is not an error; throws DdsError(context) when it is.
dds_return_t check(dds_return_t rc, std::string_view context);
[[noreturn]] void throw_on_topic(dds_return_t rc, std::string_view action, std::string_view topic, std::string_view call);
/// check() for the per-sample calls (take, write): the message, "take on topic NAME: dds_take", is
/// built only when the call failed, so a sample taken or written allocates nothing for it.
inline dds_return_t check_on_topic(dds_return_t rc, std::string_view action, std::string_view topic, std::string_view call) {
  if (rc < 0) [[unlikely]] throw_on_topic(rc, action, topic, call);
  return rc;
}

/// A random, non-zero id for one run of a publishing process (the IDL's `session_id`): a restarted
/// process starts a new session, so its readers tell its stroke 1 from the previous run's stroke 1.
std::uint64_t new_session_id();

/// Named QoS profiles. A topic's writers and readers use the same profile, so offered and
/// requested QoS always match (a mismatch in Cyclone is silent: nothing arrives).
enum class QosProfile {
  SensorData,  ///< reliable, transient-local, keep last 64 (~2 s of hand): a restarted filter catches up
  Commands,    ///< reliable, keep last 1024: voice commands, cut events must all arrive
  Strokes,     ///< reliable, transient-local, keep last 256 (~8.5 s of hand): a restarted tachi-sim gets
               ///< the samples it missed while down
  Topology,    ///< reliable, transient-local, keep last 1 per key: late joiners get the current mesh
  State,       ///< reliable, keep last 2: the newest cloth positions, never a queue of stale ones
  Status,      ///< reliable, transient-local, keep last 1 per node, 3 s liveliness lease
};

/// A topic: its DDS name, its QoS profile and (through T) its type.
template <class T>
struct TopicSpec {
  using Type = T;
  const char* name;
  QosProfile profile;
};

/// Maps a generated C type to its idlc descriptor; specialised in topics.hpp.
template <class T>
struct Descriptor;

/// DDS Security for one participant (OMG DDS Security 1.1 with Cyclone's bundled plugins):
/// authenticated by `identity`'s certificate, allowed only the topics its grant names, encrypted.
/// `dir` is what scripts/make_test_pki.sh makes: identity_ca.pem, permissions_ca.pem, governance.p7s,
/// permissions.p7s and <identity>.cert.pem / <identity>.key.pem. An empty `dir` means no security.
struct Security {
  std::string dir;
  std::string identity;
  [[nodiscard]] bool enabled() const noexcept { return !dir.empty(); }
};

/// A DDS domain participant. The domain is created with the embedded loopback config unless a
/// config file is given. Several participants of one domain may live in one process, each with its
/// own identity (security rides on the participant's QoS, not on the domain's config).
class Participant {
 public:
  explicit Participant(std::uint32_t domain, const std::string& config_file = {}, const Security& security = {});
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t handle() const noexcept { return participant_; }
  std::uint32_t domain() const noexcept { return domain_; }

 private:
  std::uint32_t domain_;
  dds_entity_t participant_;
};

/// What a reader is to the writers it matches: a stage consuming the topic, or an observer of the run
/// (the launcher's monitor and trace, the bus tools, a recorder; marked in the reader's USER_DATA, which
/// discovery carries to remote writers). A writer counting or waiting for its readers counts consumers
/// only: the launcher's trace, up before any node, must not let a recording's first frames go before the
/// filter has matched (under a lossy link discovery takes seconds, and those frames were lost).
enum class ReaderKind { Consumer, Observer };

namespace detail {
dds_entity_t create_topic(const Participant& participant, const dds_topic_descriptor_t* descriptor, const char* name);
/// The topic a writer writes on: the same type, CDR and type information as create_topic's, but each
/// sample's buffer sized to it, never taken from Cyclone's pool of freed small samples (which can hand
/// a written sample a received smaller one to grow by 4 KiB, kept as long as the writer's history keeps
/// it: idl/src/writer_sertype.cpp).
dds_entity_t create_writer_topic(const Participant& participant, const dds_topic_descriptor_t* descriptor,
                                 const char* name);
dds_entity_t create_writer(const Participant& participant, dds_entity_t topic, QosProfile profile, const char* name);
/// A tool's change to a profile's reader QoS: KeepAll keeps every sample until taken (a recorder);
/// Volatile asks for no samples written before it joined (a rate meter).
enum class ReaderQos { Profile, KeepAll, Volatile };
dds_entity_t create_reader(const Participant& participant, dds_entity_t topic, QosProfile profile, const char* name,
                           ReaderQos change = ReaderQos::Profile, ReaderKind kind = ReaderKind::Consumer);
void delete_entity(dds_entity_t entity) noexcept;
/// The writer's matched readers that are consumers (ReaderKind): observers do not count.
std::uint32_t matched_consumers(dds_entity_t writer);
std::uint32_t matched_writers(dds_entity_t reader);
/// Polls `count()` until it reaches `n` or the timeout passes.
bool wait_until_count(const std::function<std::uint32_t()>& count, std::uint32_t n, std::chrono::nanoseconds timeout);
bool wait_for_data(dds_entity_t reader, std::chrono::nanoseconds timeout);
bool wait_for_acks(dds_entity_t writer, std::chrono::nanoseconds timeout);
}  // namespace detail

/// A received sample that owns its sequences and strings (freed with the descriptor on destruction).
template <class T>
class Owned {
 public:
  Owned() noexcept { std::memset(static_cast<void*>(&msg_), 0, sizeof msg_); }
  ~Owned() { dds_sample_free(&msg_, &Descriptor<T>::value(), DDS_FREE_CONTENTS); }
  Owned(Owned&& other) noexcept {
    std::memcpy(static_cast<void*>(&msg_), &other.msg_, sizeof msg_);
    std::memset(static_cast<void*>(&other.msg_), 0, sizeof msg_);
  }
  Owned& operator=(Owned&& other) noexcept {
    if (this != &other) {
      dds_sample_free(&msg_, &Descriptor<T>::value(), DDS_FREE_CONTENTS);
      std::memcpy(static_cast<void*>(&msg_), &other.msg_, sizeof msg_);
      std::memset(static_cast<void*>(&other.msg_), 0, sizeof msg_);
    }
    return *this;
  }
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;

  T& operator*() noexcept { return msg_; }
  const T& operator*() const noexcept { return msg_; }
  T* operator->() noexcept { return &msg_; }
  const T* operator->() const noexcept { return &msg_; }

 private:
  T msg_;
};

/// A typed writer. Write a sample whose sequences point at your own buffers (`_release = false`)
/// to publish without a copy.
template <class T>
class Writer {
 public:
  Writer(const Participant& participant, const TopicSpec<T>& topic)
      : name_(topic.name),
        topic_(detail::create_writer_topic(participant, &Descriptor<T>::value(), topic.name)),
        writer_(detail::create_writer(participant, topic_, topic.profile, topic.name)) {}
  ~Writer() { detail::delete_entity(writer_); }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void write(const T& sample) { check_on_topic(dds_write(writer_, &sample), "write", name_, "dds_write"); }
  /// The matched readers that consume the topic (an observer, such as the launcher's trace, does not count).
  std::uint32_t matched_readers() const { return detail::matched_consumers(writer_); }
  /// Blocks until every matched reliable reader acknowledged all written samples; false on timeout.
  /// Call before a process exits so its last samples are not lost with it.
  bool wait_for_acks(std::chrono::nanoseconds timeout) const { return detail::wait_for_acks(writer_, timeout); }
  /// True once at least `n` consumers (not observers) have matched, false after `timeout`.
  bool wait_for_readers(std::uint32_t n, std::chrono::nanoseconds timeout) const {
    return detail::wait_until_count([this] { return matched_readers(); }, n, timeout);
  }
  dds_entity_t handle() const noexcept { return writer_; }

 private:
  std::string name_;
  dds_entity_t topic_;
  dds_entity_t writer_;
};

/// A typed reader that takes samples into a std::vector.
template <class T>
class Reader {
 public:
  Reader(const Participant& participant, const TopicSpec<T>& topic, ReaderKind kind = ReaderKind::Consumer)
      : name_(topic.name),
        topic_(detail::create_topic(participant, &Descriptor<T>::value(), topic.name)),
        reader_(detail::create_reader(participant, topic_, topic.profile, topic.name, detail::ReaderQos::Profile, kind)) {}
  ~Reader() { detail::delete_entity(reader_); }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// Takes up to `max` samples with valid data (oldest first); disposal notices are dropped.
  /// Cyclone fills the reader's own chunk of 16 receive buffers, made once with the reader: a take that
  /// finds nothing costs one dds_take, and one that finds n samples moves n out (each leaves its buffer
  /// zeroed for the next take), so a loop may look at a quiet topic every turn.
  std::vector<Owned<T>> take(std::size_t max = 256) {
    std::vector<Owned<T>> valid;
    auto& samples = chunk_->samples;
    while (valid.size() < max) {
      const std::size_t want = std::min(kChunk, max - valid.size());
      const auto n = static_cast<std::size_t>(check_on_topic(
          dds_take(reader_, chunk_->buffers.data(), chunk_->infos.data(), want, static_cast<uint32_t>(want)), "take",
          name_, "dds_take"));
      for (std::size_t i = 0; i < n; ++i)
        if (chunk_->infos[i].valid_data) valid.push_back(std::move(samples[i]));
      if (n < want) break;
    }
    return valid;
  }
  /// Blocks until data is available or the timeout passes; true when data is available.
  bool wait_for_data(std::chrono::nanoseconds timeout) const { return detail::wait_for_data(reader_, timeout); }
  std::uint32_t matched_writers() const { return detail::matched_writers(reader_); }
  /// True once at least `n` writers have matched, false after `timeout`.
  bool wait_for_writers(std::uint32_t n, std::chrono::nanoseconds timeout) const {
    return detail::wait_until_count([this] { return matched_writers(); }, n, timeout);
  }
  dds_entity_t handle() const noexcept { return reader_; }

 private:
  static constexpr std::size_t kChunk = 16;
  /// Receive buffers Cyclone deserializes into. A sample moved out leaves its buffer zeroed; a disposal
  /// notice's key fields stay until the next take reuses the buffer (Cyclone frees what it replaces).
  struct Chunk {
    Chunk() {
      for (std::size_t i = 0; i < kChunk; ++i) buffers[i] = &*samples[i];
    }
    std::array<Owned<T>, kChunk> samples;
    std::array<void*, kChunk> buffers{};
    std::array<dds_sample_info_t, kChunk> infos{};
  };

  std::string name_;
  dds_entity_t topic_;
  dds_entity_t reader_;
  std::unique_ptr<Chunk> chunk_ = std::make_unique<Chunk>();  // on the heap: 16 node statuses are ~56 KB
};

/// Waits on several readers at once: wakes when any has data, or on timeout.
class WaitSet {
 public:
  explicit WaitSet(const Participant& participant);
  ~WaitSet();
  WaitSet(const WaitSet&) = delete;
  WaitSet& operator=(const WaitSet&) = delete;

  /// Any reader with a handle(): Reader<T>, SerializedReader.
  template <class AnyReader>
  void attach(const AnyReader& reader) {
    attach_reader(reader.handle());
  }
  /// True when at least one attached reader has data; false on timeout.
  bool wait(std::chrono::nanoseconds timeout);

 private:
  void attach_reader(dds_entity_t reader);
  dds_entity_t waitset_;
  std::vector<dds_entity_t> conditions_;
};

}  // namespace tachi::bus
