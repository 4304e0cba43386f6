// `tachi record` and `tachi play`: the bus to an MCAP file and back (docs/cli.md). Every sample is
// stored as the CDR the bus carried (message encoding `cdr`) under its type's OMG IDL (schema
// encoding `omgidl`: tachi.idl), with the time the recorder received it (log_time) and its writer's
// source timestamp (publish_time), so Foxglove, `mcap` and ROS 2 tools read it as they read a bag.
#pragma once

#include "foxglove.hpp"
#include "tachi/bus/serialized.hpp"
#include "tachi/mcap/mcap.hpp"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace tachi::launcher {

struct RecordOptions {
  std::filesystem::path file;
  std::vector<std::string> topics;  ///< empty: every tachi topic
  double duration_s = 0;            ///< 0: until stopped
  std::uint64_t max_bytes = 0;      ///< 0: no limit; the recording stops once the file would pass it
  bool foxglove = false;            ///< add the derived channels in Foxglove's schemas (foxglove.hpp)
};

struct RecordResult {
  std::map<std::string, std::uint64_t> messages;  ///< per topic
  std::uint64_t total = 0;
  std::uint64_t lost = 0;  ///< samples DDS reported lost to the recorder's readers (must be 0)
  std::uint64_t bytes = 0;
  std::string ended;
};

/// Topic names that are not tachi topics, for a flag's error message (empty: all known).
std::vector<std::string> unknown_topics(const std::vector<std::string>& topics);

class Recorder {
 public:
  /// Subscribes (reliable, the topics' durability, keep-all) and creates the file.
  Recorder(const bus::Participant& participant, const RecordOptions& options);
  /// Waits up to `timeout` for samples and writes what came; false once the duration or size limit is reached.
  bool poll(std::chrono::milliseconds timeout);
  /// Takes what is left, writes the summary and closes the file.
  RecordResult finish(const std::string& ended);

 private:
  RecordOptions options_;
  std::vector<std::unique_ptr<bus::SerializedReader>> readers_;
  std::vector<std::uint16_t> channels_;
  std::vector<std::uint32_t> sequences_;
  bus::WaitSet waitset_;
  mcap::Writer writer_;
  std::chrono::steady_clock::time_point started_;
  RecordResult result_;
  bool full_ = false;
  std::optional<FoxgloveScene> scene_;
  std::uint16_t fox_cloth_ = 0, fox_hand_ = 0, fox_latency_ = 0;
  std::uint32_t fox_sequence_ = 0;
  std::vector<char> scratch_;
  void derive(const bus::TopicInfo& topic, std::span<const std::byte> cdr, std::uint64_t now_ns);
  void write_json(std::uint16_t channel, const nlohmann::json& message, std::uint64_t now_ns);
};

/// A Recorder on its own thread, for `tachi run --record`: it records from construction until stop().
class BackgroundRecorder {
 public:
  BackgroundRecorder(const bus::Participant& participant, const RecordOptions& options);
  ~BackgroundRecorder();
  RecordResult stop();

 private:
  Recorder recorder_;
  std::atomic<bool> stop_{false};
  std::string error_;  ///< written by the thread before it ends, read after join
  std::thread thread_;
};

struct PlayOptions {
  std::filesystem::path file;
  double rate = 1;                  ///< 2: twice as fast
  bool loop = false;
  std::vector<std::string> topics;  ///< empty: every tachi topic in the file
  double start_s = 0;               ///< skip the first S seconds of the recording
  double wait_s = 0;                ///< wait up to S s for a reader of every played topic before starting
};

struct PlayResult {
  std::map<std::string, std::uint64_t> published;  ///< per topic
  std::uint64_t skipped = 0;                       ///< messages of channels that are not tachi topics (or another type)
};

/// Publishes the file's messages again with their recorded spacing (log_time / rate). Stops at the
/// end (or, with `loop`, on SIGINT/SIGTERM). Throws naming the file on a malformed one.
PlayResult play(const bus::Participant& participant, const PlayOptions& options);

}  // namespace tachi::launcher
