// `tachi hz` and `tachi bw`: a topic's rate, its jitter and its bandwidth over the last samples, as
// `ros2 topic hz` / `ros2 topic bw` report them (rate = (n - 1) / (t_n - t_1) over a sliding window
// of arrival times; jitter = the standard deviation of the intervals; bandwidth = the bytes that
// arrived after the window's first sample over the same span). Pure: times and sizes in, figures out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

namespace tachi::launcher {

struct TopicRate {
  std::size_t samples = 0;        ///< in the window
  double rate_hz = 0;
  double min_interval_s = 0, max_interval_s = 0, jitter_s = 0;  ///< jitter: standard deviation of the intervals
  double bytes_per_s = 0;
  double mean_bytes = 0, min_bytes = 0, max_bytes = 0;
};

class TopicRateWindow {
 public:
  explicit TopicRateWindow(std::size_t window = 10000) : window_(window < 2 ? 2 : window) {}
  /// One sample that arrived at `time_ns` (any monotonic clock) with `bytes` bytes.
  void add(std::int64_t time_ns, std::size_t bytes);
  /// The figures over the window; nullopt before two samples came.
  [[nodiscard]] std::optional<TopicRate> rate() const;

 private:
  std::size_t window_;
  std::deque<std::pair<std::int64_t, std::size_t>> samples_;
};

/// `ros2 topic hz`'s report: "average rate: 30.012\n\tmin: 0.031s max: 0.035s std dev: 0.00100s window: 31".
[[nodiscard]] std::string hz_report(const TopicRate& r);
/// `ros2 topic bw`'s report: "5.86 KB/s from 31 messages\n\tMessage size mean: 0.19 KB min: 0.19 KB max: 0.19 KB".
[[nodiscard]] std::string bw_report(const TopicRate& r);

}  // namespace tachi::launcher
