// "waiting for tachi-sim on domain 7": every process says, every few seconds, that it waits for a
// peer that does not come, instead of running silently (a viewer without a simulator once ran ten
// minutes without a word). Each main loop calls `check` with whether the peer is matched.
#pragma once

#include <chrono>
#include <optional>
#include <string>

namespace tachi::common {

class PeerWait {
 public:
  using Clock = std::chrono::steady_clock;
  /// `peer` names what is missing ("tachi-sim"), `domain` where it is looked for.
  PeerWait(std::string peer, unsigned domain, std::chrono::milliseconds every = std::chrono::seconds(3),
           Clock::time_point start = Clock::now());

  /// The warning to print now, if any: once `every` has passed without the peer, then once per
  /// `every` while it stays away. A peer that leaves starts the count again.
  [[nodiscard]] std::optional<std::string> check(bool peer_present, Clock::time_point now = Clock::now());
  /// check() and, when it has something to say, spdlog::warn it.
  void warn_if_waiting(bool peer_present);

 private:
  std::string message_;
  std::chrono::milliseconds every_;
  Clock::time_point absent_since_;
  Clock::time_point last_warning_;
  bool present_ = false;
};

}  // namespace tachi::common
