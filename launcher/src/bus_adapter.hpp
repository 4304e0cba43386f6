// The launcher's edge to the DDS bus: heartbeats -> NodeReport, the run's trace (hand samples,
// strokes and cuts as they pass on the bus, for latency.png and trajectory.png), and the
// JSON form of every tachi message for `tachi echo`.
#pragma once

#include "tachi/bus/topics.hpp"
#include "tachi/launcher/status.hpp"
#include "tachi/launcher/topic_rate.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

namespace tachi::launcher {

[[nodiscard]] NodeReport from_msg(const tachi_msg_NodeStatus& msg);

/// Watches one run's domain: keeps the status board current and writes the trace CSVs
/// (trace/hands.csv, trace/strokes.csv). It does not read the cloth states: at 128 x 128 one more
/// reader of 196 KB states would load the simulator it measures. The end-to-end delays per depth
/// frame come from the simulator's own summary (`latency_ms`).
class RunMonitor {
 public:
  RunMonitor(const bus::Participant& participant, const std::filesystem::path& trace_dir);
  /// Takes whatever arrived, waiting up to `timeout` for something.
  void poll(StatusBoard& board, std::chrono::milliseconds timeout);
  [[nodiscard]] std::uint64_t cut_events() const { return cut_events_; }
  /// The trace file a full disk refused (the trace stops there), if one did.
  [[nodiscard]] const std::optional<std::filesystem::path>& disk_full() const { return disk_full_; }

 private:
  bus::Reader<tachi_msg_NodeStatus> status_;
  bus::Reader<tachi_msg_RawHandSample> hands_;
  bus::Reader<tachi_msg_StrokeSample> strokes_;
  bus::Reader<tachi_msg_CutEvent> cuts_;
  bus::WaitSet waitset_;
  std::ofstream hands_csv_, strokes_csv_;
  std::filesystem::path trace_dir_;
  std::optional<std::filesystem::path> disk_full_;
  std::uint64_t cut_events_ = 0;
};

/// Whether `topic` is one of tachi's topics (bus::for_each_topic).
[[nodiscard]] bool known_topic(const std::string& topic);

struct EchoOptions {
  std::uint64_t count = 0;  ///< 0: until stopped
  bool full = false;        ///< sequences whole, not {"length": n, "first": [8 elements]}
  std::string field;        ///< a dotted path into the sample (e.g. position_m.0, metrics.fps); empty: the whole sample
  std::chrono::milliseconds timeout{0};  ///< 0: no limit
};

/// A sample's JSON form, `tachi echo`'s line (sequences longer than 8 summarised unless `full`).
template <class T>
[[nodiscard]] nlohmann::json to_json(const T& msg, bool full);

/// The value at a dotted path ("position_m.0", "metrics.fps") of a JSON sample; nullptr when there is none.
[[nodiscard]] const nlohmann::json* field_at(const nlohmann::json& sample, const std::string& path);

/// Prints samples of `topic` as JSON lines on stdout (or, with a field, that field's value); returns
/// how many. Throws std::invalid_argument naming the path when a sample has no such field.
std::uint64_t echo(const bus::Participant& participant, const std::string& topic, const EchoOptions& options);

/// `tachi hz` / `tachi bw`: prints the topic's rate and jitter (or bandwidth) every second, over the
/// last `window` samples, until stopped or `duration` passed (0: no limit). Returns the last figures.
std::optional<TopicRate> watch_rate(const bus::Participant& participant, const bus::TopicInfo& topic, bool bandwidth,
                                    std::size_t window, std::chrono::milliseconds duration);

}  // namespace tachi::launcher
