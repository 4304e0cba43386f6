#include "tachi/common/peer_wait.hpp"

#include <spdlog/spdlog.h>

namespace tachi::common {

PeerWait::PeerWait(std::string peer, unsigned domain, std::chrono::milliseconds every, Clock::time_point start)
    : message_("waiting for " + std::move(peer) + " on domain " + std::to_string(domain)),
      every_(every),
      absent_since_(start),
      last_warning_(start) {}

std::optional<std::string> PeerWait::check(bool peer_present, Clock::time_point now) {
  if (peer_present) {
    present_ = true;
    return std::nullopt;
  }
  if (present_) {  // it left: count from now
    present_ = false;
    absent_since_ = last_warning_ = now;
    return std::nullopt;
  }
  if (now - last_warning_ < every_) return std::nullopt;
  last_warning_ = now;
  const auto waited = std::chrono::duration_cast<std::chrono::seconds>(now - absent_since_);
  return message_ + " (" + std::to_string(waited.count()) + " s)";
}

void PeerWait::warn_if_waiting(bool peer_present) {
  if (const auto message = check(peer_present)) spdlog::warn("{}", *message);
}

}  // namespace tachi::common
