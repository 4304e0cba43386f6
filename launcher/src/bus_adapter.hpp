// The launcher's edge to the DDS bus: heartbeats -> NodeReport, the run's trace (hand samples,
// strokes and cuts as they pass on the bus, for latency.png and trajectory.png), and the
// JSON form of every tachi message for `tachi echo`.
#pragma once

#include "tachi/bus/topics.hpp"
#include "tachi/launcher/status.hpp"

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

 private:
  bus::Reader<tachi_msg_NodeStatus> status_;
  bus::Reader<tachi_msg_RawHandSample> hands_;
  bus::Reader<tachi_msg_StrokeSample> strokes_;
  bus::Reader<tachi_msg_CutEvent> cuts_;
  bus::WaitSet waitset_;
  std::ofstream hands_csv_, strokes_csv_;
  std::uint64_t cut_events_ = 0;
};

/// The topic names `tachi echo` knows, and one JSON line per sample of such a topic (sequences
/// longer than 8 elements summarised as {"length": n, "first": [...]} unless `full`).
[[nodiscard]] bool known_topic(const std::string& topic);
/// Prints up to `count` samples (0: until stopped) of `topic` as JSON lines on stdout; returns how many.
std::uint64_t echo(const bus::Participant& participant, const std::string& topic, std::uint64_t count, bool full,
                   std::chrono::milliseconds timeout);

}  // namespace tachi::launcher
