// The run as the nodes' heartbeats (tachi/node/status) describe it: the latest report per node,
// the status line drawn from them, and the figures summary.json takes from them. Heartbeats come
// over DDS, so nodes on other hosts count the same as local ones. Metric names: docs/dds.md.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace tachi::launcher {

/// One heartbeat, in the launcher's terms.
struct NodeReport {
  std::string node;   ///< "tachi-sensor"
  std::string host;
  std::uint32_t pid = 0;
  std::string state;  ///< starting, running, degraded, stopping
  std::int64_t time_ns = 0;
  std::uint64_t messages_in = 0;
  std::uint64_t messages_out = 0;
  std::uint64_t rejected = 0;
  std::string detail;
  std::map<std::string, double> metrics;
};

class StatusBoard {
 public:
  /// Keeps the newest report per node name (a restarted node replaces its predecessor).
  void update(NodeReport report);
  [[nodiscard]] const std::map<std::string, NodeReport>& nodes() const { return nodes_; }
  /// A node's metric, if it reported it.
  [[nodiscard]] std::optional<double> metric(const std::string& node, const std::string& name) const;
  /// A stage's capture -> output delay percentile ("p50", "p99"), ms.
  [[nodiscard]] std::optional<double> stage_latency(const std::string& stage, const char* percentile) const;
  /// Strokes the simulator received (its heartbeat), else the filter's count: a mouse-blade run has no filter.
  [[nodiscard]] std::optional<double> strokes() const;

  /// One line: frames, fps, tracked %, gate state and source, strokes, cuts, pieces, per-stage
  /// latency p50, restarts. Figures not reported yet show as "-".
  [[nodiscard]] std::string line(int restarts) const;
  /// The heartbeat part of summary.json: frames, tracked_frames, strokes, cuts, pieces,
  /// fallen_pieces, cut_length_m, e2e_p50_ms/e2e_p99_ms, <stage>_p50_ms/<stage>_p99_ms.
  [[nodiscard]] nlohmann::json summary() const;

 private:
  std::map<std::string, NodeReport> nodes_;
};

/// "tachi-sensor" for "sensor" and so on: the name a node's heartbeat carries.
[[nodiscard]] std::string node_process(const std::string& node);

}  // namespace tachi::launcher
