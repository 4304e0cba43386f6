#include "tachi/launcher/status.hpp"

#include <array>
#include <cmath>
#include <cstdio>

namespace tachi::launcher {
namespace {

const std::array<const char*, 4> kStages{"sensor", "filter", "sim", "viewer"};

// GateState and GateSource as the filter reports them (numeric values of tachi.idl's enums).
std::string gate_text(std::optional<double> gate, std::optional<double> source) {
  static const std::array<const char*, 4> kGates{"idle", "cutting", "holding", "grabbing"};
  static const std::array<const char*, 4> kSources{"-", "threshold", "voice", "mouse"};
  if (!gate) return "-";
  const auto g = static_cast<std::size_t>(*gate);
  std::string text = g < kGates.size() ? kGates[g] : "?";
  if (source) {
    const auto s = static_cast<std::size_t>(*source);
    if (s > 0 && s < kSources.size()) text += std::string("/") + kSources[s];
  }
  return text;
}

std::string number(std::optional<double> v, const char* format = "%.0f") {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, *v);
  return buf;
}

}  // namespace

std::string node_process(const std::string& node) { return "tachi-" + node; }

void StatusBoard::update(NodeReport report) {
  auto& slot = nodes_[report.node];
  // Samples of two processes of one name (a restart) may arrive out of order: the newer one counts.
  if (slot.node.empty() || report.pid != slot.pid || report.time_ns >= slot.time_ns) slot = std::move(report);
}

std::optional<double> StatusBoard::metric(const std::string& node, const std::string& name) const {
  const auto n = nodes_.find(node_process(node));
  if (n == nodes_.end()) return std::nullopt;
  const auto m = n->second.metrics.find(name);
  if (m == n->second.metrics.end()) return std::nullopt;
  return m->second;
}

std::optional<double> StatusBoard::stage_latency(const std::string& stage, const char* percentile) const {
  // The viewer reports the age of the state it shows (capture -> image) under its own name.
  if (const auto v = metric(stage, std::string("latency_") + percentile + "_ms")) return v;
  return metric(stage, std::string("state_age_") + percentile + "_ms");
}

std::optional<double> StatusBoard::strokes() const {
  // The simulator's count, as summary.json's: the strokes it received, from the filter's hand or from the
  // viewer's mouse blade (a run without a filter). The filter's own count stands in before the simulator reports.
  if (const auto sim = metric("sim", "strokes")) return sim;
  return metric("filter", "strokes");
}

std::string StatusBoard::line(int restarts) const {
  const auto frames = metric("sensor", "frames");
  const auto tracked = metric("sensor", "tracked_frames");
  std::optional<double> tracked_pct;
  if (frames && tracked && *frames > 0) tracked_pct = 100.0 * *tracked / *frames;
  std::string text = "frames " + number(frames) + " @ " + number(metric("sensor", "fps"), "%.1f") + " fps, tracked " +
                     number(tracked_pct) + "%, gate " + gate_text(metric("filter", "gate"), metric("filter", "gate_opened_by")) +
                     ", strokes " + number(strokes()) + ", cuts " + number(metric("sim", "cuts")) +
                     ", pieces " + number(metric("sim", "pieces")) + ", p50 ms";
  for (const char* stage : kStages) text += std::string(" ") + stage + " " + number(stage_latency(stage, "p50"), "%.1f");
  text += ", restarts " + std::to_string(restarts);
  return text;
}

nlohmann::json StatusBoard::summary() const {
  nlohmann::json s = nlohmann::json::object();
  const auto put = [&](const char* key, const char* node, const char* name) {
    if (const auto v = metric(node, name)) s[key] = *v;
  };
  const auto count = [&](const char* key, const char* node, const char* name) {
    if (const auto v = metric(node, name)) s[key] = std::llround(*v);
  };
  count("frames", "sensor", "frames");
  count("tracked_frames", "sensor", "tracked_frames");
  if (const auto n = strokes()) s["strokes"] = std::llround(*n);
  count("cuts", "sim", "cuts");
  count("pieces", "sim", "pieces");
  count("fallen_pieces", "sim", "fallen_pieces");
  put("cut_length_m", "sim", "cut_length_m");
  // End to end is the simulator's figure: capture of the depth frame -> the published cloth state.
  put("e2e_p50_ms", "sim", "latency_p50_ms");
  put("e2e_p99_ms", "sim", "latency_p99_ms");
  for (const char* stage : kStages)
    for (const char* p : {"p50", "p99"})
      if (const auto v = stage_latency(stage, p)) s[std::string(stage) + "_" + p + "_ms"] = *v;
  std::uint64_t rejected = 0;
  for (const auto& [name, report] : nodes_) rejected += report.rejected;
  s["rejected_inputs"] = rejected;
  return s;
}

}  // namespace tachi::launcher
