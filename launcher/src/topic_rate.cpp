#include "tachi/launcher/topic_rate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tachi::launcher {

void TopicRateWindow::add(std::int64_t time_ns, std::size_t bytes) {
  samples_.emplace_back(time_ns, bytes);
  while (samples_.size() > window_) samples_.pop_front();
}

std::optional<TopicRate> TopicRateWindow::rate() const {
  if (samples_.size() < 2) return std::nullopt;
  TopicRate r;
  r.samples = samples_.size();
  const double span_s = static_cast<double>(samples_.back().first - samples_.front().first) * 1e-9;
  if (span_s <= 0) return std::nullopt;
  r.rate_hz = static_cast<double>(samples_.size() - 1) / span_s;
  // Welford's running mean and variance of the intervals (Knuth, TAOCP vol. 2, 4.2.2).
  double mean = 0, m2 = 0;
  std::size_t n = 0;
  r.min_interval_s = 1e300;
  double bytes_after_first = 0;
  r.min_bytes = 1e300;
  double all_bytes = 0;
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    const auto size = static_cast<double>(samples_[i].second);
    all_bytes += size;
    r.min_bytes = std::min(r.min_bytes, size);
    r.max_bytes = std::max(r.max_bytes, size);
    if (i == 0) continue;
    bytes_after_first += size;
    const double dt = static_cast<double>(samples_[i].first - samples_[i - 1].first) * 1e-9;
    r.min_interval_s = std::min(r.min_interval_s, dt);
    r.max_interval_s = std::max(r.max_interval_s, dt);
    ++n;
    const double delta = dt - mean;
    mean += delta / static_cast<double>(n);
    m2 += delta * (dt - mean);
  }
  r.jitter_s = std::sqrt(m2 / static_cast<double>(n));
  r.bytes_per_s = bytes_after_first / span_s;
  r.mean_bytes = all_bytes / static_cast<double>(samples_.size());
  return r;
}

std::string hz_report(const TopicRate& r) {
  char text[160];
  std::snprintf(text, sizeof text, "average rate: %.3f\n\tmin: %.3fs max: %.3fs std dev: %.5fs window: %zu", r.rate_hz,
                r.min_interval_s, r.max_interval_s, r.jitter_s, r.samples);
  return text;
}

namespace {
std::string human_bytes(double b) {
  char text[32];
  if (b >= 1e6) std::snprintf(text, sizeof text, "%.2f MB", b / 1e6);
  else if (b >= 1e3) std::snprintf(text, sizeof text, "%.2f KB", b / 1e3);
  else std::snprintf(text, sizeof text, "%.0f B", b);
  return text;
}
}  // namespace

std::string bw_report(const TopicRate& r) {
  return human_bytes(r.bytes_per_s) + "/s from " + std::to_string(r.samples) + " messages\n\tMessage size mean: " +
         human_bytes(r.mean_bytes) + " min: " + human_bytes(r.min_bytes) + " max: " + human_bytes(r.max_bytes);
}

}  // namespace tachi::launcher
