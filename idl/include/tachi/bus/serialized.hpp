// Samples of any tachi topic in their serialized form (the CDR the bus carries: a 4-byte
// encapsulation header, then the payload, DDSI-RTPS 2.5 section 10), for tools that treat every
// topic alike: `tachi record` stores it as it came (no deserialization on the recording path),
// `tachi play` writes it again, `tachi hz|bw` count it.
#pragma once

#include "tachi/bus/topics.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace tachi::bus {

/// idl/tachi.idl, embedded at build time: the OMG IDL of every type (self-contained, no preprocessor
/// directives), which a recording stores as each channel's schema (MCAP schema encoding `omgidl`).
extern const char* const kTachiIdl;

/// What a tool's reader is for. A recorder keeps every sample until it took it (a slow disk costs
/// memory, never a sample) and gets what transient-local writers kept for late joiners; a rate meter
/// wants only samples written from now on (a burst of kept ones is not a rate).
enum class ReaderRole { Recorder, RateMeter };

/// Takes samples of one topic as CDR bytes.
class SerializedReader {
 public:
  /// `each(cdr, source_ns)`: one valid sample's serialized bytes (valid during the call) and its
  /// writer's source timestamp (ns since the epoch).
  using Each = std::function<void(std::span<const std::byte> cdr, std::int64_t source_ns)>;

  SerializedReader(const Participant& participant, const TopicInfo& topic, ReaderRole role);
  ~SerializedReader();
  SerializedReader(const SerializedReader&) = delete;
  SerializedReader& operator=(const SerializedReader&) = delete;

  /// Takes everything that arrived; returns how many valid samples went to `each`.
  std::size_t take(const Each& each);
  /// Samples DDS reported lost to this reader so far (DDS SAMPLE_LOST status).
  std::uint64_t lost();
  const TopicInfo& topic() const noexcept { return topic_; }
  dds_entity_t handle() const noexcept { return reader_; }

 private:
  TopicInfo topic_;
  dds_entity_t topic_entity_;
  dds_entity_t reader_;
  std::uint64_t lost_ = 0;
};

/// Writes samples of one topic given as CDR bytes (e.g. read back from a recording).
class SerializedWriter {
 public:
  SerializedWriter(const Participant& participant, const TopicInfo& topic);
  ~SerializedWriter();
  SerializedWriter(const SerializedWriter&) = delete;
  SerializedWriter& operator=(const SerializedWriter&) = delete;

  /// Checks `cdr` against the topic's type (bounds, lengths, byte order: Cyclone's normalizer) and
  /// writes it. Throws std::invalid_argument, naming the topic, when it is not a sample of that type.
  void write(std::span<const std::byte> cdr);
  bool wait_for_readers(std::uint32_t n, std::chrono::nanoseconds timeout) const;
  bool wait_for_acks(std::chrono::nanoseconds timeout) const { return detail::wait_for_acks(writer_, timeout); }
  const TopicInfo& topic() const noexcept { return topic_; }

 private:
  TopicInfo topic_;
  dds_entity_t topic_entity_;
  dds_entity_t writer_;
  std::vector<char> payload_;  ///< reused: the normalizer works in place
};

/// Reads `cdr` (encapsulation header + payload) into `sample` (zeroed memory of the descriptor's type;
/// its sequences are allocated, to be freed with dds_sample_free), after Cyclone's normalizer checked
/// it against the type. Throws std::invalid_argument naming `what` when it is not a sample of the type.
void deserialize_into(const dds_topic_descriptor_t& descriptor, std::span<const std::byte> cdr, void* sample,
                      std::vector<char>& scratch, const std::string& what);

/// A typed sample from its CDR (e.g. a recorder deriving other channels from what it stores).
template <class T>
Owned<T> deserialize(std::span<const std::byte> cdr, std::vector<char>& scratch) {
  Owned<T> sample;
  deserialize_into(Descriptor<T>::value(), cdr, &*sample, scratch, Descriptor<T>::value().m_typename);
  return sample;
}

/// Serializes a typed sample the way the bus does (XCDR1, this host's byte order, with the 4-byte
/// encapsulation header): for tests and derived channels that need CDR without a round trip.
std::vector<std::byte> serialize(const dds_topic_descriptor_t& descriptor, const void* sample);

}  // namespace tachi::bus
