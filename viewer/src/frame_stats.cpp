#include "tachi/viewer/frame_stats.hpp"

#include <algorithm>
#include <cmath>

namespace tachi::viewer {

void FrameStats::frame(std::chrono::steady_clock::time_point now, std::optional<double> state_age_ms) {
  ++frames_;
  recent_.push_back(now);
  while (!recent_.empty() && now - recent_.front() > std::chrono::seconds(1)) recent_.pop_front();
  if (state_age_ms && std::isfinite(*state_age_ms)) {
    ages_.push_back(*state_age_ms);
    if (ages_.size() > kAgeWindow) ages_.pop_front();
  }
}

double FrameStats::fps() const {
  if (recent_.size() < 2) return 0.0;
  const double span_s = std::chrono::duration<double>(recent_.back() - recent_.front()).count();
  return span_s > 0.0 ? static_cast<double>(recent_.size() - 1) / span_s : 0.0;
}

std::optional<double> FrameStats::age_ms(double q) const {
  if (ages_.empty()) return std::nullopt;
  std::vector<double> sorted(ages_.begin(), ages_.end());
  const auto rank = static_cast<std::ptrdiff_t>(std::lround(std::clamp(q, 0.0, 1.0) * static_cast<double>(sorted.size() - 1)));
  std::nth_element(sorted.begin(), sorted.begin() + rank, sorted.end());
  return sorted[static_cast<std::size_t>(rank)];
}

}  // namespace tachi::viewer
