#include "tachi/bus/serialized.hpp"

#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata.h>

#include <array>
#include <bit>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>

namespace tachi::bus {
namespace {

// Encapsulation identifiers (DDSI-RTPS 2.5 table 10.3; DDS-XTypes 1.3 table 60), big-endian on the
// wire: CDR_BE 0x0000, CDR_LE 0x0001, CDR2_BE 0x0006, CDR2_LE 0x0007, D_CDR2_BE 0x0008, D_CDR2_LE 0x0009.
// Parameter-list encodings (PL_CDR*) belong to mutable types, which tachi.idl has none of.
struct Encapsulation {
  bool little_endian;
  std::uint32_t xcdr_version;
};
std::optional<Encapsulation> encapsulation(std::span<const std::byte> cdr) {
  if (cdr.size() < 4 || cdr[0] != std::byte{0}) return std::nullopt;
  switch (std::to_integer<int>(cdr[1])) {
    case 0x00: return Encapsulation{false, 1};
    case 0x01: return Encapsulation{true, 1};
    case 0x06: case 0x08: return Encapsulation{false, 2};
    case 0x07: case 0x09: return Encapsulation{true, 2};
    default: return std::nullopt;
  }
}

}  // namespace

SerializedReader::SerializedReader(const Participant& participant, const TopicInfo& topic, ReaderRole role)
    : topic_(topic),
      topic_entity_(detail::create_topic(participant, topic.descriptor, topic.name)),
      reader_(detail::create_reader(participant, topic_entity_, topic.profile, topic.name,
                                    role == ReaderRole::Recorder ? detail::ReaderQos::KeepAll : detail::ReaderQos::Volatile,
                                    ReaderKind::Observer)) {}

SerializedReader::~SerializedReader() { detail::delete_entity(reader_); }

std::size_t SerializedReader::take(const Each& each) {
  constexpr std::uint32_t kChunk = 64;
  std::array<ddsi_serdata*, kChunk> samples{};
  std::array<dds_sample_info_t, kChunk> infos{};
  std::size_t valid = 0;
  while (true) {
    const dds_return_t n = check_on_topic(dds_takecdr(reader_, samples.data(), kChunk, infos.data(), DDS_ANY_STATE), "take",
                                          topic_.name, "dds_takecdr");
    for (dds_return_t i = 0; i < n; ++i) {
      ddsi_serdata* sample = samples[static_cast<std::size_t>(i)];
      if (infos[static_cast<std::size_t>(i)].valid_data) {
        // A reference into Cyclone's own buffer: no copy on the way to the recorder.
        const std::uint32_t size = ddsi_serdata_size(sample);
        ddsrt_iovec_t ref{};
        ddsi_serdata* held = ddsi_serdata_to_ser_ref(sample, 0, size, &ref);
        each({static_cast<const std::byte*>(ref.iov_base), static_cast<std::size_t>(ref.iov_len)},
             infos[static_cast<std::size_t>(i)].source_timestamp);
        ddsi_serdata_to_ser_unref(held, &ref);
        ++valid;
      }
      ddsi_serdata_unref(sample);
    }
    if (static_cast<std::uint32_t>(n) < kChunk) break;
  }
  return valid;
}

std::uint64_t SerializedReader::lost() {
  dds_sample_lost_status_t status{};
  check(dds_get_sample_lost_status(reader_, &status), "dds_get_sample_lost_status");
  return status.total_count;
}

SerializedWriter::SerializedWriter(const Participant& participant, const TopicInfo& topic)
    : topic_(topic),
      topic_entity_(detail::create_writer_topic(participant, topic.descriptor, topic.name)),
      writer_(detail::create_writer(participant, topic_entity_, topic.profile, topic.name)) {}

SerializedWriter::~SerializedWriter() { detail::delete_entity(writer_); }

bool SerializedWriter::wait_for_readers(std::uint32_t n, std::chrono::nanoseconds timeout) const {
  return detail::wait_until_count([this] { return detail::matched_consumers(writer_); }, n, timeout);
}

void deserialize_into(const dds_topic_descriptor_t& descriptor, std::span<const std::byte> cdr, void* sample,
                      std::vector<char>& scratch, const std::string& what) {
  const auto enc = encapsulation(cdr);
  if (!enc) throw std::invalid_argument("not " + what + ": unknown CDR encapsulation header");
  scratch.assign(reinterpret_cast<const char*>(cdr.data()) + 4, reinterpret_cast<const char*>(cdr.data() + cdr.size()));
  const bool swap = enc->little_endian != (std::endian::native == std::endian::little);
  // Cyclone's normalizer checks every length and bound against the type's ops (and swaps bytes), so
  // a damaged file is refused here instead of being read past its end.
  std::uint32_t offset = 0;
  const auto size = static_cast<std::uint32_t>(scratch.size());
  if (dds_stream_normalize_data(scratch.data(), &offset, size, swap, enc->xcdr_version, descriptor.m_ops) == nullptr)
    throw std::invalid_argument("not " + what + ": its CDR does not match the type");
  dds_istream_t in{};
  dds_istream_init(&in, size, scratch.data(), enc->xcdr_version);
  dds_stream_read(&in, static_cast<char*>(sample), descriptor.m_ops);
  dds_istream_fini(&in);
}

void SerializedWriter::write(std::span<const std::byte> cdr) {
  const auto free_sample = [this](void* s) { dds_sample_free(s, topic_.descriptor, DDS_FREE_ALL); };
  std::unique_ptr<void, decltype(free_sample)> sample(dds_alloc(topic_.descriptor->m_size), free_sample);
  deserialize_into(*topic_.descriptor, cdr, sample.get(), payload_,
                   std::string("a sample of ") + topic_.name + " (" + std::string(topic_.type_name()) + ")");
  check_on_topic(dds_write(writer_, sample.get()), "write", topic_.name, "dds_write");
}

std::vector<std::byte> serialize(const dds_topic_descriptor_t& descriptor, const void* sample) {
  dds_ostream_t out{};
  dds_ostream_init(&out, 0, 1);
  dds_stream_write(&out, static_cast<const char*>(sample), descriptor.m_ops);
  std::vector<std::byte> cdr(4 + out.m_index);
  cdr[1] = std::byte{std::endian::native == std::endian::little ? 1 : 0};  // CDR_LE / CDR_BE, options 0
  if (out.m_index > 0) std::memcpy(cdr.data() + 4, out.m_buffer, out.m_index);
  dds_ostream_fini(&out);
  return cdr;
}

}  // namespace tachi::bus
