#include "tachi/mcap/mcap.hpp"

#include "tachi/common/disk_full.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>

namespace tachi::mcap {
namespace {

constexpr std::array<std::byte, 8> kMagic{std::byte{0x89}, std::byte{'M'}, std::byte{'C'}, std::byte{'A'},
                                          std::byte{'P'},  std::byte{'0'}, std::byte{'\r'}, std::byte{'\n'}};
enum Op : std::uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kMessageIndex = 0x07, kChunkIndex = 0x08, kStatistics = 0x0B, kSummaryOffset = 0x0E, kDataEnd = 0x0F,
};

// Little-endian serialization (MCAP spec "Serialization"): integers, uint32-length strings, maps.
struct Out {
  std::vector<std::byte>& b;
  template <class U>
  void u(U v) {
    for (std::size_t i = 0; i < sizeof(U); ++i) b.push_back(static_cast<std::byte>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xff));
  }
  void bytes(const void* p, std::size_t n) {
    const auto* c = static_cast<const std::byte*>(p);
    b.insert(b.end(), c, c + n);
  }
  void str(const std::string& s) {
    u(static_cast<std::uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  // A record: opcode, uint64 content length (patched once the content is written), content.
  template <class F>
  void record(std::uint8_t op, F&& content) {
    u(op);
    const std::size_t at = b.size();
    u(std::uint64_t{0});
    content();
    const std::uint64_t length = b.size() - at - 8;
    for (std::size_t i = 0; i < 8; ++i) b[at + i] = static_cast<std::byte>((length >> (8 * i)) & 0xff);
  }
  // A uint32 byte-length prefix patched after the elements (arrays and maps).
  template <class F>
  void prefixed(F&& elements) {
    const std::size_t at = b.size();
    u(std::uint32_t{0});
    elements();
    const auto length = static_cast<std::uint32_t>(b.size() - at - 4);
    for (std::size_t i = 0; i < 4; ++i) b[at + i] = static_cast<std::byte>((length >> (8 * i)) & 0xff);
  }
};

void schema_record(Out& o, const Schema& s) {
  o.record(kSchema, [&] {
    o.u(s.id);
    o.str(s.name);
    o.str(s.encoding);
    o.str(s.data);  // uint32 length-prefixed bytes: the same layout as a string
  });
}

void channel_record(Out& o, const Channel& c) {
  o.record(kChannel, [&] {
    o.u(c.id);
    o.u(c.schema_id);
    o.str(c.topic);
    o.str(c.message_encoding);
    o.prefixed([&] {
      for (const auto& [k, v] : c.metadata) {
        o.str(k);
        o.str(v);
      }
    });
  });
}

// Bounds-checked little-endian reading; errors name the file and the offset.
struct In {
  const std::byte* p;
  std::size_t n;
  std::size_t at = 0;
  const std::filesystem::path* file;
  std::uint64_t base = 0;  ///< file offset of p[0], for messages

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(file->string() + ": not a valid MCAP file: " + what + " at byte " + std::to_string(base + at));
  }
  void need(std::size_t k) const {
    if (k > n - at) fail("a record runs past its end");
  }
  template <class U>
  U u() {
    need(sizeof(U));
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i) v |= static_cast<std::uint64_t>(std::to_integer<std::uint8_t>(p[at + i])) << (8 * i);
    at += sizeof(U);
    return static_cast<U>(v);
  }
  std::span<const std::byte> bytes(std::size_t k) {
    need(k);
    std::span<const std::byte> s{p + at, k};
    at += k;
    return s;
  }
  std::string str() {
    const auto k = u<std::uint32_t>();
    const auto s = bytes(k);
    return {reinterpret_cast<const char*>(s.data()), s.size()};
  }
};

Schema parse_schema(In& in) {
  Schema s;
  s.id = in.u<std::uint16_t>();
  s.name = in.str();
  s.encoding = in.str();
  s.data = in.str();
  return s;
}

Channel parse_channel(In& in) {
  Channel c;
  c.id = in.u<std::uint16_t>();
  c.schema_id = in.u<std::uint16_t>();
  c.topic = in.str();
  c.message_encoding = in.str();
  const auto length = in.u<std::uint32_t>();
  In map{in.bytes(length).data(), length, 0, in.file, in.base + in.at - length};
  while (map.at < map.n) {
    std::string k = map.str();
    c.metadata[k] = map.str();
  }
  return c;
}

// Calls `each(opcode, content)` for the records in `in` until it returns false or `in` ends.
template <class Each>
void for_each_record(In& in, Each&& each) {
  while (in.at < in.n) {
    const auto op = in.u<std::uint8_t>();
    const auto length = in.u<std::uint64_t>();
    if (length > in.n - in.at) in.fail("a record runs past the end");
    In content{in.p + in.at, static_cast<std::size_t>(length), 0, in.file, in.base + in.at};
    in.at += static_cast<std::size_t>(length);
    if (!each(op, content)) return;
  }
}

std::vector<std::byte> read_file(const std::filesystem::path& file) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (f == nullptr) throw std::runtime_error(file.string() + ": cannot open: " + std::strerror(errno));
  std::vector<std::byte> data;
  std::array<std::byte, 1 << 16> buffer;
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), f)) > 0;) data.insert(data.end(), buffer.begin(), buffer.begin() + n);
  std::fclose(f);
  return data;
}

}  // namespace

std::uint32_t crc32(std::span<const std::byte> data, std::uint32_t crc) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (const auto b : data) crc = table[(crc ^ std::to_integer<std::uint32_t>(b)) & 0xff] ^ (crc >> 8);
  return ~crc;
}

Writer::Writer(const std::filesystem::path& file, const std::string& profile, const std::string& library, std::size_t chunk_bytes)
    : path_(file), chunk_bytes_(chunk_bytes) {
  file_ = std::fopen(file.c_str(), "wb");
  if (file_ == nullptr) throw std::runtime_error("cannot write " + file.string() + ": " + std::strerror(errno));
  std::vector<std::byte> head;
  Out o{head};
  o.bytes(kMagic.data(), kMagic.size());
  o.record(kHeader, [&] {
    o.str(profile);
    o.str(library);
  });
  put(head);
  chunk_.reserve(chunk_bytes + (1 << 20));
}

Writer::~Writer() {
  try {
    close();
  } catch (...) {  // a destructor must not throw; close() explicitly to see the error
  }
}

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  schemas_.push_back({static_cast<std::uint16_t>(schemas_.size() + 1), name, encoding, data});  // 0 means "no schema"
  schema_written_.push_back(false);
  return schemas_.back().id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                  const std::map<std::string, std::string>& metadata) {
  channels_.push_back({static_cast<std::uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata});
  channel_written_.push_back(false);
  return channels_.back().id;
}

std::uint64_t Writer::closed_size_with(std::uint16_t channel, std::size_t data_bytes) const {
  const auto schema_size = [](const Schema& x) { return 1 + 8 + 2 + 12 + x.name.size() + x.encoding.size() + x.data.size(); };
  const auto channel_size = [](const Channel& c) {
    std::uint64_t n = 1 + 8 + 4 + 12 + c.topic.size() + c.message_encoding.size();
    for (const auto& [k, v] : c.metadata) n += 8 + k.size() + v.size();
    return n;
  };
  constexpr std::uint64_t kChunkHeader = 1 + 8 + 8 + 8 + 8 + 4 + 4 + 8;
  constexpr std::uint64_t kChunkIndex = 1 + 8 + 8 + 8 + 8 + 8 + 4 + 8 + 4 + 8 + 8;
  constexpr std::uint64_t kMessageIndexHeader = 1 + 8 + 2 + 4;
  const std::size_t channels_in_chunk = chunk_index_.size() + (chunk_index_.contains(channel) ? 0 : 1);
  std::uint64_t messages_in_chunk = 1;
  for (const auto& [c, entries] : chunk_index_) messages_in_chunk += entries.size();
  // The open chunk with the message (and its channel's records if not yet written), and its indexes.
  std::uint64_t n = file_offset_ + kChunkHeader + chunk_.size() + 1 + 8 + 2 + 4 + 8 + 8 + data_bytes;
  if (!channel_written_.at(channel)) {
    n += channel_size(channels_[channel]);
    if (channels_[channel].schema_id != 0) n += schema_size(schemas_[channels_[channel].schema_id - 1]);
  }
  n += channels_in_chunk * (kMessageIndexHeader + 10) + messages_in_chunk * 16;
  // Data end, summary (every schema and channel again, statistics, chunk indexes), offsets, footer, magic.
  n += 1 + 8 + 4;
  for (const auto& x : schemas_) n += schema_size(x);
  for (const auto& c : channels_) n += channel_size(c);
  n += 1 + 8 + 8 + 2 + 4 * 4 + 8 + 8 + 4 + 10 * (stats_.channel_message_counts.size() + 1);
  for (const auto& ci : chunk_indexes_) n += ci.size();
  n += kChunkIndex + 10 * channels_in_chunk;
  n += 4 * (1 + 8 + 1 + 8 + 8) + 1 + 8 + 20 + kMagic.size();
  return n;
}

void Writer::put(std::span<const std::byte> bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    tachi::common::throw_write_error(path_, "cannot write " + path_.string() + ": " + std::strerror(errno));
  data_crc_ = crc32(bytes, data_crc_);
  file_offset_ += bytes.size();
}

void Writer::write(const Message& m) {
  if (closed_) throw std::logic_error("mcap::Writer::write after close");
  Out o{chunk_};
  // A channel's schema and channel records go into the chunk before its first message.
  const Channel& channel = channels_.at(m.channel_id);
  if (!channel_written_[m.channel_id]) {
    if (channel.schema_id != 0 && !schema_written_[channel.schema_id - 1]) {
      schema_record(o, schemas_[channel.schema_id - 1]);
      schema_written_[channel.schema_id - 1] = true;
    }
    channel_record(o, channel);
    channel_written_[m.channel_id] = true;
  }
  const bool first = chunk_index_.empty();
  chunk_index_[m.channel_id].emplace_back(m.log_time, chunk_.size());
  o.record(kMessage, [&] {
    o.u(m.channel_id);
    o.u(m.sequence);
    o.u(m.log_time);
    o.u(m.publish_time);
    o.bytes(m.data.data(), m.data.size());
  });
  chunk_start_ = first ? m.log_time : std::min(chunk_start_, m.log_time);
  chunk_end_ = first ? m.log_time : std::max(chunk_end_, m.log_time);
  stats_.message_start_time = stats_.message_count == 0 ? m.log_time : std::min(stats_.message_start_time, m.log_time);
  stats_.message_end_time = std::max(stats_.message_end_time, m.log_time);
  ++stats_.message_count;
  ++stats_.channel_message_counts[m.channel_id];
  if (chunk_.size() >= chunk_bytes_) flush_chunk();
}

void Writer::flush_chunk() {
  if (chunk_.empty()) return;
  const std::uint64_t chunk_offset = file_offset_;
  std::vector<std::byte> rec;
  rec.reserve(64);
  Out o{rec};
  // The chunk record's header, then its records straight from the buffer (no copy of the records).
  o.u(std::uint8_t{kChunk});
  o.u(std::uint64_t{8 + 8 + 8 + 4 + 4 + 8 + chunk_.size()});
  o.u(chunk_start_);
  o.u(chunk_end_);
  o.u(std::uint64_t{chunk_.size()});
  o.u(crc32(chunk_));
  o.str("");  // no compression
  o.u(std::uint64_t{chunk_.size()});
  put(rec);
  put(chunk_);
  const std::uint64_t chunk_length = file_offset_ - chunk_offset;
  // One Message Index record per channel in the chunk, right after it.
  std::vector<std::byte> indexes;
  Out mi{indexes};
  std::map<std::uint16_t, std::uint64_t> index_offsets;
  for (const auto& [channel, entries] : chunk_index_) {
    index_offsets[channel] = file_offset_ + indexes.size();
    mi.record(kMessageIndex, [&] {
      mi.u(channel);
      mi.prefixed([&] {
        for (const auto& [time, offset] : entries) {
          mi.u(time);
          mi.u(offset);
        }
      });
    });
  }
  put(indexes);
  std::vector<std::byte> ci;
  Out c{ci};
  c.record(kChunkIndex, [&] {
    c.u(chunk_start_);
    c.u(chunk_end_);
    c.u(chunk_offset);
    c.u(chunk_length);
    c.prefixed([&] {
      for (const auto& [channel, offset] : index_offsets) {
        c.u(channel);
        c.u(offset);
      }
    });
    c.u(std::uint64_t{indexes.size()});
    c.str("");
    c.u(std::uint64_t{chunk_.size()});
    c.u(std::uint64_t{chunk_.size()});
  });
  chunk_indexes_.push_back(std::move(ci));
  ++stats_.chunk_count;
  chunk_.clear();
  chunk_index_.clear();
}

void Writer::close() {
  if (closed_) return;
  closed_ = true;
  flush_chunk();
  std::vector<std::byte> end;
  Out e{end};
  e.record(kDataEnd, [&] { e.u(data_crc_); });
  put(end);

  // The summary section, grouped by opcode (schemas, channels, statistics, chunk indexes), then one
  // Summary Offset record per group, then the footer: an indexed reader starts from the end.
  const std::uint64_t summary_start = file_offset_;
  std::vector<std::byte> summary;
  Out s{summary};
  std::vector<std::tuple<std::uint8_t, std::uint64_t, std::uint64_t>> groups;
  const auto group = [&](std::uint8_t op, auto&& write_group) {
    const std::size_t at = summary.size();
    write_group();
    if (summary.size() > at) groups.emplace_back(op, summary_start + at, summary.size() - at);
  };
  group(kSchema, [&] {
    for (const auto& schema : schemas_) schema_record(s, schema);
  });
  group(kChannel, [&] {
    for (const auto& channel : channels_) channel_record(s, channel);
  });
  stats_.schema_count = static_cast<std::uint16_t>(schemas_.size());
  stats_.channel_count = static_cast<std::uint32_t>(channels_.size());
  group(kStatistics, [&] {
    s.record(kStatistics, [&] {
      s.u(stats_.message_count);
      s.u(stats_.schema_count);
      s.u(stats_.channel_count);
      s.u(std::uint32_t{0});  // attachments
      s.u(std::uint32_t{0});  // metadata
      s.u(stats_.chunk_count);
      s.u(stats_.message_start_time);
      s.u(stats_.message_end_time);
      s.prefixed([&] {
        for (const auto& [channel, count] : stats_.channel_message_counts) {
          s.u(channel);
          s.u(count);
        }
      });
    });
  });
  group(kChunkIndex, [&] {
    for (const auto& ci : chunk_indexes_) s.bytes(ci.data(), ci.size());
  });
  const std::uint64_t summary_offset_start = summary_start + summary.size();
  for (const auto& [op, start, length] : groups)
    s.record(kSummaryOffset, [&] {
      s.u(op);
      s.u(start);
      s.u(length);
    });
  // Footer: its CRC covers the summary from its start through the footer's summary_offset_start.
  s.u(std::uint8_t{kFooter});
  s.u(std::uint64_t{20});
  s.u(summary_start);
  s.u(summary_offset_start);
  s.u(crc32(summary));
  s.bytes(kMagic.data(), kMagic.size());
  put(summary);
  const bool flushed = std::fflush(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) tachi::common::throw_write_error(path_, "cannot write " + path_.string() + ": " + std::strerror(errno));
}

void read(const std::filesystem::path& file, const ReadCallbacks& callbacks) {
  const std::vector<std::byte> data = read_file(file);
  In in{data.data(), data.size(), 0, &file};
  if (data.size() < kMagic.size() || !std::equal(kMagic.begin(), kMagic.end(), data.begin()))
    in.fail("no MCAP magic at its start");
  in.at = kMagic.size();
  bool stop = false;
  const auto one = [&](std::uint8_t op, In& content) {
    switch (op) {
      case kSchema: {
        const Schema s = parse_schema(content);
        if (callbacks.schema) callbacks.schema(s);
        break;
      }
      case kChannel: {
        const Channel c = parse_channel(content);
        if (callbacks.channel) callbacks.channel(c);
        break;
      }
      case kMessage: {
        Message m;
        m.channel_id = content.u<std::uint16_t>();
        m.sequence = content.u<std::uint32_t>();
        m.log_time = content.u<std::uint64_t>();
        m.publish_time = content.u<std::uint64_t>();
        m.data = content.bytes(content.n - content.at);
        if (callbacks.message && !callbacks.message(m)) stop = true;
        break;
      }
      default: break;  // indexes, statistics, private records: not needed to read the messages
    }
    return !stop;
  };
  for_each_record(in, [&](std::uint8_t op, In& content) {
    if (op == kDataEnd || op == kFooter) return false;
    if (op != kChunk) return one(op, content);
    content.u<std::uint64_t>();  // message start and end time
    content.u<std::uint64_t>();
    const auto uncompressed_size = content.u<std::uint64_t>();
    const auto crc = content.u<std::uint32_t>();
    const std::string compression = content.str();
    if (!compression.empty()) content.fail("chunk compressed with " + compression + " (only uncompressed chunks are read)");
    const auto length = content.u<std::uint64_t>();
    if (length != uncompressed_size) content.fail("chunk records' length differs from its uncompressed size");
    const auto records = content.bytes(static_cast<std::size_t>(length));
    if (crc != 0 && crc32(records) != crc) content.fail("chunk CRC mismatch");
    In inner{records.data(), records.size(), 0, &file, content.base + content.at - records.size()};
    for_each_record(inner, one);
    return !stop;
  });
}

Statistics read_statistics(const std::filesystem::path& file) {
  const std::vector<std::byte> data = read_file(file);
  In in{data.data(), data.size(), 0, &file};
  constexpr std::size_t kFooterRecord = 1 + 8 + 20;
  if (data.size() < 2 * kMagic.size() + kFooterRecord || !std::equal(kMagic.begin(), kMagic.end(), data.end() - 8))
    in.fail("no MCAP magic at its end (was the recording stopped before it closed the file?)");
  in.at = data.size() - kMagic.size() - kFooterRecord;
  if (in.u<std::uint8_t>() != kFooter || in.u<std::uint64_t>() != 20) in.fail("no footer before the closing magic");
  const auto summary_start = in.u<std::uint64_t>();
  Statistics stats;
  if (summary_start == 0) return stats;
  if (summary_start >= data.size()) in.fail("summary start past the end");
  In summary{data.data(), data.size() - kMagic.size() - kFooterRecord, static_cast<std::size_t>(summary_start), &file};
  for_each_record(summary, [&](std::uint8_t op, In& r) {
    if (op != kStatistics) return true;
    stats.message_count = r.u<std::uint64_t>();
    stats.schema_count = r.u<std::uint16_t>();
    stats.channel_count = r.u<std::uint32_t>();
    r.u<std::uint32_t>();
    r.u<std::uint32_t>();
    stats.chunk_count = r.u<std::uint32_t>();
    stats.message_start_time = r.u<std::uint64_t>();
    stats.message_end_time = r.u<std::uint64_t>();
    const auto length = r.u<std::uint32_t>();
    r.need(length);
    for (const std::size_t end = r.at + length; r.at < end;) {
      const auto channel = r.u<std::uint16_t>();
      stats.channel_message_counts[channel] = r.u<std::uint64_t>();
    }
    return false;
  });
  return stats;
}

}  // namespace tachi::mcap
