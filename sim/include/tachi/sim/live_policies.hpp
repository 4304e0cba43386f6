// The live simulator's timing policies, apart from the bus so that they are tested without processes:
// how often topology changes go out (a token bucket and a keyframe period), how long a stroke waits for a
// publisher that went away, which re-delivered samples a journal replay already applied, and when the
// fixed-step loop gives up on a backlog. SimNode (sim/src/node.cpp) drives them with the steady clock.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>

namespace tachi::sim {

using LiveClock = std::chrono::steady_clock;

/// Topology deltas at a bounded rate and a keyframe for late joiners (docs/dds.md, "tachi/cloth/topology").
/// A token bucket of `rate_hz` tokens a second holding at most `burst`: a 30 Hz hand gets a delta with each
/// cutting sample while a burst of cuts cannot exceed the bound (the classic leaky/token bucket of network
/// traffic shaping, Turner 1986). A keyframe (the whole topology) goes out at most once per `keyframe_period`
/// after deltas were sent, so a reader that missed a delta recovers.
class TopologyRate {
 public:
  TopologyRate(LiveClock::time_point now, double rate_hz = 30.0, double burst = 2.0,
               LiveClock::duration keyframe_period = std::chrono::seconds(1));
  /// Refills the bucket up to `now`; true when it holds a token for a delta.
  bool delta_allowed(LiveClock::time_point now);
  /// A delta went out: spends its token, and a keyframe is owed.
  void delta_sent();
  /// True when a keyframe is due now (deltas went out since the last one, and the period has passed);
  /// the caller then publishes it, and the next is due a period later.
  bool take_keyframe(LiveClock::time_point now);
  /// A keyframe is owed (deltas went out since the last one): the last publication at shutdown sends it.
  [[nodiscard]] bool keyframe_owed() const { return keyframe_owed_; }
  /// A delta went out at shutdown, outside the bound: only the keyframe is owed.
  void final_delta_sent() { keyframe_owed_ = true; }

 private:
  double rate_hz_;
  double burst_;
  LiveClock::duration keyframe_period_;
  double tokens_;
  LiveClock::time_point last_refill_;
  LiveClock::time_point last_keyframe_;
  bool keyframe_owed_ = false;
};

/// A stroke whose publisher went away stays open for `grace` for it to come back: a filter restarted on its
/// journal (tachi run restarts it in ~0.5 s) carries the same stroke on under the same session. Only the
/// stroke that lost its publisher is closed: another filter's new stroke (its own session) goes on.
class StrokePublisherGrace {
 public:
  enum class Verdict { None, PublisherGone, PublisherBack, CloseStroke, GraceOver };
  explicit StrokePublisherGrace(LiveClock::duration grace = std::chrono::seconds(2)) : grace_(grace) {}
  /// A hand sample applied: `cutting` names the session of the newest cutting sample.
  /// PublisherBack when the publisher that went away sends again.
  Verdict on_sample(std::uint64_t session_id, bool cutting);
  /// Once per loop: whether any stroke publisher is matched and whether a stroke is open.
  /// PublisherGone when the last one left mid-stroke; CloseStroke when the grace ran out and the stroke open is
  /// still the one that lost its publisher (GraceOver when it is another's); None otherwise.
  Verdict tick(bool has_publisher, bool stroke_open, LiveClock::time_point now);
  [[nodiscard]] LiveClock::duration grace() const { return grace_; }

 private:
  LiveClock::duration grace_;
  bool had_publisher_ = false;
  std::optional<LiveClock::time_point> gone_at_;
  std::uint64_t cutting_session_ = 0;  // the filter session of the newest cutting sample
  std::uint64_t gone_session_ = 0;     // ... when the stroke's publisher went away
};

/// When a run on a recording ends (`tachi-sim --exit-when-idle`): `settle` after the last hand sample, the cloth
/// having settled. Not while a hand source upstream is starting: a sensor or filter the launcher restarted
/// replays its recording or journal (1-2 s under load) before it publishes again, and a run that ended in that
/// gap lost the rest of its stroke. A source counts as starting from its NODE_STARTING heartbeat to its next
/// state, for at most `max_hold`, so one that dies while starting cannot keep the run open; the settle time
/// counts again from the moment it is running.
class IdleEnd {
 public:
  IdleEnd(LiveClock::duration settle, LiveClock::time_point now,
          LiveClock::duration max_hold = std::chrono::seconds(10))
      : settle_(settle), max_hold_(max_hold), last_activity_(now) {}
  /// A hand sample was applied (or replayed from the journal).
  void hand_sample(LiveClock::time_point now);
  /// A heartbeat of a hand source (by node name): `starting` while it has not published yet.
  void source_status(const std::string& node, bool starting, LiveClock::time_point now);
  /// True when the run is over: a hand sample was seen, no source is starting, and `settle` has passed since the
  /// last sample or the last source came up.
  [[nodiscard]] bool over(LiveClock::time_point now) const;

 private:
  LiveClock::duration settle_;
  LiveClock::duration max_hold_;
  bool had_sample_ = false;
  LiveClock::time_point last_activity_;
  std::map<std::string, LiveClock::time_point> starting_since_;  // per node name
};

/// What a journal replay applied: per (sensor, filter session) the newest sample time. A restarted filter's
/// history delivers those samples again; they are not applied twice.
class ReplayedSamples {
 public:
  ReplayedSamples() = default;
  explicit ReplayedSamples(std::map<std::pair<std::uint32_t, std::uint64_t>, std::int64_t> newest)
      : newest_(std::move(newest)) {}
  [[nodiscard]] bool already_applied(std::uint32_t sensor_id, std::uint64_t session_id, std::int64_t time_ns) const;

 private:
  std::map<std::pair<std::uint32_t, std::uint64_t>, std::int64_t> newest_;
};

/// The fixed-step schedule of the solver: a step every `period`; a loop that fell more than `max_backlog`
/// periods behind drops the backlog instead of racing to catch up (and counts an overrun).
class StepSchedule {
 public:
  StepSchedule(LiveClock::duration period, LiveClock::time_point start, int max_backlog = 5)
      : period_(period), next_(start), max_backlog_(max_backlog) {}
  [[nodiscard]] bool due(LiveClock::time_point now) const { return now >= next_; }
  /// How long the loop may wait for input before the next step (zero when it is due).
  [[nodiscard]] LiveClock::duration until_next(LiveClock::time_point now) const {
    return std::max(next_ - now, LiveClock::duration::zero());
  }
  /// After a step finished at `now`: schedules the next; true when that dropped a backlog (an overrun).
  bool stepped(LiveClock::time_point now);
  [[nodiscard]] std::uint64_t overruns() const { return overruns_; }

 private:
  LiveClock::duration period_;
  LiveClock::time_point next_;
  int max_backlog_;
  std::uint64_t overruns_ = 0;
};

}  // namespace tachi::sim
