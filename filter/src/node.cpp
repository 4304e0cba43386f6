#include "tachi/filter/node.hpp"

#include "bus_adapter.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/input_guard.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/latency.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/filter/journal.hpp"
#include "tachi/filter/stroke_filter.hpp"

#include <spdlog/spdlog.h>

#include <optional>
#include <thread>
#include <vector>

namespace tachi::filter {
namespace {
using namespace std::chrono_literals;

// A Kinect v1 sees 0.4-4 m; a camera-frame hand beyond 20 m on any axis is a faulty or hostile peer.
constexpr float kMaxHandRange_m = 20.0F;
// A cloth particle further than this from the origin is a faulty state. Not 100 m, as it was: a cut-off
// piece falls without end at its terminal speed (g / damping: 19.6 m/s at the default 0.5 1/s), so
// 6 s after a piece fell every state was refused and the distance gate kept a stale cloth (found by
// bench/launcher/soak.py: 92,776 states refused in 17 minutes). 1e6 m is 14 hours of falling, and
// still refuses a peer's 1e30.
constexpr float kMaxClothRange_m = 1e6F;
// Hand samples carry no session id: a sensor whose clock jumps back by more than this restarted.
constexpr std::int64_t kSensorRestartGap_ns = 1'000'000'000;
// The largest cloth tachi-sim simulates live, cut up to twice over, xyz each.
constexpr std::size_t kMaxClothFloats = bus::topics::kMaxClothStateFloats;
}  // namespace

struct FilterNode::Impl {
  Impl(const FilterConfig& filter_config, const std::string& journal_file, bus::Participant& dds)
      : config(filter_config), journal_path(journal_file), hands(dds, bus::topics::raw_hand),
        voice(dds, bus::topics::voice_command), cloth(dds, bus::topics::cloth_state), strokes(dds, bus::topics::stroke),
        waitset(dds), heartbeat(dds, "tachi-filter"),
        // Hostile or faulty input is refused before the filter sees it, and counted in the heartbeat.
        guard([this](std::string_view reason) {
          heartbeat.count_rejected(reason);
          if (heartbeat.rejected() == 1 || heartbeat.rejected() % 100 == 0)
            spdlog::warn("{} input samples rejected (last: {})", heartbeat.rejected(), reason);
        }),
        filter(config), session_id(recover()), catch_up(journal && !journal->recovered().empty(), CatchUpGate::Clock::now()),
        waiting_for_sensor("tachi-sensor", dds.domain()) {
    waitset.attach(hands);
    waitset.attach(voice);
    waitset.attach(cloth);
    spdlog::info("tachi-filter on domain {}: gate {}, smoother {}", dds.domain(), to_string(config.gate.mode),
                 to_string(config.smoother.kind));
  }

  // No lost cuts: a journal left by a killed run is replayed first (same state, same session), and
  // the hand samples it already holds are skipped when the sensor's history delivers them again.
  // The session id of this run: the journal's, or a new one.
  std::uint64_t recover() {
    if (journal_path.empty()) return bus::new_session_id();
    journal.emplace(journal_path, config, bus::new_session_id());
    if (!journal->recovered().empty()) {
      const auto t0 = std::chrono::steady_clock::now();
      auto replayed = replay(journal->recovered(), filter);
      processed = std::move(replayed.processed);
      // The last sample was journaled before it was published: if the kill fell in between, the
      // simulator never got it. Sent again (the strokes topic is transient-local): at worst a duplicate.
      if (replayed.last) batch.push_back(to_msg(replayed.last->second, replayed.last->first, journal->session_id()));
      spdlog::info("tachi-filter: replayed {} journal records from {} in {:.0f} ms: session {:x} goes on at stroke {} ({})",
                   journal->recovered().size(), journal_path,
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(),
                   journal->session_id(), filter.gate().status().stroke_id, to_string(filter.gate().status().phase));
    }
    return journal->session_id();
  }

  void journal_append(const FilterJournalRecord& record) {
    if (!journal || journal->append(record) || journal_full_said) return;
    journal_full_said = true;
    spdlog::warn("tachi-filter: journal {} reached {} MB; no longer journaling (a restart from here would lose the rest)",
                 journal_path, FilterJournal::kMaxBytes >> 20);
  }

  void take_voice() {
    // Commands first: one spoken before a hand sample arrived applies to that sample.
    for (const auto& c : voice.take()) {
      static constexpr const char* kNames[] = {"start", "stop", "grab", "release"};
      const auto command = from_msg(*c);
      spdlog::info("voice command {} (\"{}\")", kNames[static_cast<int>(command)], c->phrase);
      if (const auto why = filter.on_voice(command)) spdlog::warn("{}", *why);
      journal_append({FilterJournalRecord::Kind::Voice, 0, {}, {}, command});
      // A command changes the gate: monitors (and tests) see it applied at once, not at the next beat.
      heartbeat.set_metric("voice_commands", static_cast<double>(++voice_commands));
      heartbeat.publish_at_next_update();
    }
  }

  void take_hands() {
    for (const auto& h : hands.take()) {
      if (processed.contains(h->sensor_id, h->capture_time_ns)) {
        ++redelivered;  // processed before the restart (or a frame sent twice): not a new sample
        continue;
      }
      ++in_count;
      if (h->tracked && !guard.position(h->position_m.x, h->position_m.y, h->position_m.z, kMaxHandRange_m)) continue;
      if (!guard.time(h->sensor_id, h->capture_time_ns, bus::InputGuard::now_ns(), kSensorRestartGap_ns)) continue;
      const auto hand = from_msg(*h);
      const auto stroke = filter.on_hand(hand);
      processed.add(h->sensor_id, h->capture_time_ns);
      journal_append({FilterJournalRecord::Kind::Hand, h->sensor_id, hand,
                      {stroke.distance_to_cloth_m, stroke.hand_outside_cloth, {}}, {}});
      auto msg = to_msg(stroke, h->sensor_id, session_id);
      msg.acquired_ns = h->acquired_ns;  // the depth frame's time rides on to the simulator
      batch.push_back(msg);
      heartbeat.set_metric("strokes", stroke.stroke_id);
      heartbeat.set_metric("outliers", static_cast<double>(filter.outliers()));  // impossibly fast samples
      heartbeat.set_metric("gate", static_cast<double>(msg.gate));
      heartbeat.set_metric("gate_opened_by", static_cast<double>(msg.opened_by));
    }
  }

  void publish_batch() {
    // Journaled before published: a sample the simulator has, the journal has.
    if (journal) journal->flush();
    for (const auto& msg : batch) {
      strokes.write(msg);
      if (msg.acquired_ns > 0) latency.add_since(msg.acquired_ns, common::wall_clock_ns());
      ++out_count;
    }
    if (!batch.empty()) {
      heartbeat.set_metric("latency_p50_ms", latency.percentile(50));
      heartbeat.set_metric("latency_p99_ms", latency.percentile(99));
    }
    batch.clear();
  }

  // The cloth after the hands: a 128 x 128 state is 196 KB to copy and scan, and the hand samples
  // must not wait for it (end-to-end latency); the gate then uses the cloth as of one state earlier.
  void take_cloth() {
    auto states = cloth.take();
    if (states.empty()) return;
    const auto& newest = *states.back();
    if (guard.size(newest.positions._length, kMaxClothFloats, 3) &&
        guard.positions(newest.positions._buffer, newest.positions._length, kMaxClothRange_m)) {
      filter.on_cloth_state({newest.positions._buffer, newest.positions._length});
      catch_up.cloth_seen();
      heartbeat.set_metric("cloth_states", static_cast<double>(++cloth_states));
      if (cloth_states == 1) heartbeat.publish_at_next_update();  // the distance gate has a cloth from now on
    }
  }

  bool spin_once() {
    waitset.wait(100ms);
    take_voice();
    const bool taking_hands = catch_up.take_hands(CatchUpGate::Clock::now());
    if (taking_hands) take_hands();
    publish_batch();
    if (!taking_hands) std::this_thread::sleep_for(5ms);  // the waitset stays triggered by the waiting hands
    waiting_for_sensor.warn_if_waiting(hands.matched_writers() > 0);
    take_cloth();
    heartbeat.set_metric("redelivered", static_cast<double>(redelivered));
    heartbeat.update(tachi_msg_NODE_RUNNING, in_count, out_count, "gate " + to_string(config.gate.mode));
    return true;
  }

  const FilterConfig config;
  const std::string journal_path;
  bus::Reader<tachi_msg_RawHandSample> hands;
  bus::Reader<tachi_msg_VoiceCommand> voice;
  std::uint64_t voice_commands = 0;  ///< applied (the heartbeat's "voice_commands")
  std::uint64_t cloth_states = 0;    ///< accepted (the heartbeat's "cloth_states")
  bus::Reader<tachi_msg_ClothState> cloth;
  bus::Writer<tachi_msg_StrokeSample> strokes;
  bus::WaitSet waitset;
  bus::Heartbeat heartbeat;
  bus::InputGuard guard;
  StrokeFilter filter;
  std::optional<FilterJournal> journal;
  ProcessedSamples processed;
  std::vector<tachi_msg_StrokeSample> batch;  // to publish; first the resent last sample of a recovered journal
  bool journal_full_said = false;
  const std::uint64_t session_id;
  CatchUpGate catch_up;
  std::uint64_t in_count = 0;
  std::uint64_t out_count = 0;
  std::uint64_t redelivered = 0;
  common::LatencyWindow latency;
  common::PeerWait waiting_for_sensor;
};

FilterNode::FilterNode(const FilterConfig& config, const std::string& journal, bus::Participant& dds)
    : impl_(std::make_unique<Impl>(config, journal, dds)) {}
FilterNode::~FilterNode() = default;
bool FilterNode::spin_once() { return impl_->spin_once(); }

int FilterNode::finish() {
  spdlog::info("stopping: {} hand samples in, {} stroke samples out", impl_->in_count, impl_->out_count);
  return common::kExitOk;
}

}  // namespace tachi::filter
