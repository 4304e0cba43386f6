// MCAP, the container of ROS 2 bags and Foxglove (https://mcap.dev/spec, format version 0): a writer
// that stores messages in chunks, each followed by its message indexes, and ends the file with a
// summary section (schemas, channels, statistics, chunk indexes) and its summary offsets, so indexed
// readers find any channel or time without scanning; and a reader for what the writer makes (the
// records of any MCAP file without compression). Chunks are stored uncompressed: on loopback the
// disk is not the bottleneck, and a compressor would take CPU from the pipeline being recorded.
// Pure logic: files and bytes, no DDS.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace tachi::mcap {

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), the checksum MCAP uses: `crc` continues a
/// running checksum (start with 0).
std::uint32_t crc32(std::span<const std::byte> data, std::uint32_t crc = 0);

struct Schema {
  std::uint16_t id = 0;
  std::string name;      ///< e.g. tachi::msg::RawHandSample
  std::string encoding;  ///< e.g. omgidl, jsonschema
  std::string data;
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  ///< e.g. cdr, json
  std::map<std::string, std::string> metadata;
};

struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;      ///< ns since the epoch: when the recorder received it
  std::uint64_t publish_time = 0;  ///< ns since the epoch: the writer's source timestamp
  std::span<const std::byte> data;
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0, message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

class Writer {
 public:
  /// Creates `file` (truncating it); throws std::runtime_error naming it when it cannot.
  /// A chunk is closed once its records reach `chunk_bytes`.
  Writer(const std::filesystem::path& file, const std::string& profile, const std::string& library,
         std::size_t chunk_bytes = 4 << 20);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  std::uint16_t add_channel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                            const std::map<std::string, std::string>& metadata = {});
  void write(const Message& message);
  /// Writes the last chunk, the summary and the footer; the file is complete after this.
  void close();
  /// Bytes in the file so far plus those buffered in the open chunk.
  [[nodiscard]] std::uint64_t bytes() const noexcept { return file_offset_ + chunk_.size(); }
  /// At most the size the file would have if a message of `data_bytes` on `channel` were written and the
  /// file closed right after (open chunk, its indexes, data end, summary, footer): what a size limit checks.
  [[nodiscard]] std::uint64_t closed_size_with(std::uint16_t channel, std::size_t data_bytes) const;
  [[nodiscard]] const Statistics& statistics() const noexcept { return stats_; }

 private:
  void put(std::span<const std::byte> bytes);
  void flush_chunk();

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_offset_ = 0;
  std::uint32_t data_crc_ = 0;
  std::size_t chunk_bytes_;
  std::vector<std::byte> chunk_;  ///< the open chunk's records
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;  ///< channel -> (log time, offset)
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::vector<std::vector<std::byte>> chunk_indexes_;  ///< Chunk Index records for the summary
  std::vector<bool> schema_written_, channel_written_;
  Statistics stats_;
  bool closed_ = false;
};

/// What a reader met in a file, in file order.
struct ReadCallbacks {
  std::function<void(const Schema&)> schema;
  std::function<void(const Channel&)> channel;
  std::function<bool(const Message&)> message;  ///< false: stop reading
};

/// Reads the records of `file` in order (descending into chunks, checking each chunk's CRC) until
/// its data section ends. Throws std::runtime_error naming the file and the byte offset on anything
/// malformed (bad magic, a record that runs past the end, a chunk whose CRC does not match, a
/// compressed chunk).
void read(const std::filesystem::path& file, const ReadCallbacks& callbacks);

/// The file's Statistics record, found through the footer's summary section (nullopt-like empty
/// statistics with channel_count 0 when the file has no summary).
Statistics read_statistics(const std::filesystem::path& file);

}  // namespace tachi::mcap
