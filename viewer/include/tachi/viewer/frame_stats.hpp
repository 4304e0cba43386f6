// The viewer's own figures for the HUD and the heartbeat: frames per second over the last second and
// the age of the shown cloth state (now - ClothState.acquired_ns: the end-to-end latency of what is on
// screen) over the last few hundred frames.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

namespace tachi::viewer {

class FrameStats {
 public:
  static constexpr std::size_t kAgeWindow = 600;

  /// A frame was shown at `now`; `state_age_ms` when the shown state carried acquired_ns.
  void frame(std::chrono::steady_clock::time_point now, std::optional<double> state_age_ms);

  [[nodiscard]] double fps() const;
  [[nodiscard]] std::uint64_t frames() const { return frames_; }
  /// Quantile q (0..1) of the recent state ages, or nothing before the first.
  [[nodiscard]] std::optional<double> age_ms(double q) const;
  /// The newest hand sample's latency (capture -> its first showing): what the HUD shows. It holds
  /// while the hand rests; the time since that sample is no delay of the pipeline.
  [[nodiscard]] std::optional<double> latest_age_ms() const {
    return ages_.empty() ? std::nullopt : std::optional<double>(ages_.back());
  }

 private:
  std::deque<std::chrono::steady_clock::time_point> recent_;  // frame times of the last second
  std::deque<double> ages_;
  std::uint64_t frames_ = 0;
};

}  // namespace tachi::viewer
