// tachi-filter as stages: the DDS stage (FilterNode: raw hands and voice commands in, gated strokes out, with
// journal recovery) and the offline driver (a hand CSV and a voice CSV in, a stroke CSV out). The process is a
// deployment choice: filter/main.cpp only parses flags. FilterNode links from tachi_filter_node (DDS);
// CatchUpGate, the offline driver and the voice CSV are pure tachi_filter.
#pragma once

#include "tachi/filter/config.hpp"

#include <chrono>
#include <memory>
#include <string>

namespace tachi::bus {
class Participant;
}

namespace tachi::filter {

/// A gate recovered from a journal measures the hand against the cloth it was cutting: the hand samples that
/// wait wait (up to `timeout`) for the simulator's next state rather than being judged against the flat rest
/// cloth. A filter that recovered nothing takes hands at once.
class CatchUpGate {
 public:
  using Clock = std::chrono::steady_clock;
  CatchUpGate(bool recovering, Clock::time_point now, Clock::duration timeout = std::chrono::seconds(1))
      : recovering_(recovering), due_(now + timeout) {}
  void cloth_seen() { cloth_seen_ = true; }
  [[nodiscard]] bool take_hands(Clock::time_point now) const { return !recovering_ || cloth_seen_ || now >= due_; }

 private:
  bool recovering_;
  Clock::time_point due_;
  bool cloth_seen_ = false;
};

struct OfflineFilterOptions {
  std::string hands_csv;   ///< the sensor's CSV
  std::string out_csv;     ///< frame,stamp_ns,x,y,z,gate,stroke_id
  std::string voice_csv;   ///< tachi-voice's output; time 0 = the first hand sample (empty: none)
  bool camera_frame = false;
};

/// Filters a hand CSV into a stroke CSV (voice commands applied at their times). The exit code; throws
/// naming the file it cannot read or write.
int run_offline(const OfflineFilterOptions& options, const FilterConfig& config);

class FilterNode {
 public:
  /// Replays `journal` (when not empty) into the filter, then joins `dds`. `dds` must outlive the node.
  FilterNode(const FilterConfig& config, const std::string& journal, bus::Participant& dds);
  ~FilterNode();
  FilterNode(const FilterNode&) = delete;
  FilterNode& operator=(const FilterNode&) = delete;

  /// Waits (100 ms at most) for input; voice commands, then hands, go through the filter and out as strokes;
  /// then the newest cloth state. Always true: the filter runs until stopped.
  bool spin_once();
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::filter
