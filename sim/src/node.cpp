#include "tachi/sim/node.hpp"

#include "bus_adapter.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/input_guard.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/latency.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/sim/export.hpp"
#include "tachi/sim/journal.hpp"
#include "tachi/sim/live_policies.hpp"
#include "tachi/sim/session.hpp"
#include "tachi/sim/summary.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>

namespace tachi::sim {
namespace {
using Clock = LiveClock;

tachi_msg_CutEvent cut_msg(std::uint32_t cloth_id, std::uint32_t version, const CutReport& report,
                           std::vector<tachi_msg_GridCoord>& line, std::uint64_t session_id) {
  line.clear();
  for (const GridCoord g : report.stroke.cut_line)
    line.push_back({static_cast<std::uint16_t>(g.u), static_cast<std::uint16_t>(g.v)});
  tachi_msg_CutEvent msg{};
  msg.cloth_id = cloth_id;
  msg.stroke_id = report.stroke_id;
  msg.sensor_id = report.sensor_id;  // which hand source cut (camera hand, mouse blade)
  msg.topology_version = version;
  msg.cut_line._buffer = line.data();
  msg.cut_line._length = msg.cut_line._maximum = static_cast<std::uint32_t>(line.size());
  msg.cut_line._release = false;
  msg.particles_duplicated = static_cast<std::uint32_t>(report.stroke.particles_duplicated);
  msg.pieces = static_cast<std::uint32_t>(report.pieces);
  msg.fallen_pieces = static_cast<std::uint32_t>(report.fallen_pieces);
  msg.cut_length_m = report.stroke.cut_length_m;
  msg.session_id = session_id;
  return msg;
}


SessionOptions live_session_options(const OfflineOptions& shared, const LiveOptions& live) {
  SessionOptions options = session_options(shared);
  options.hand_radius_m = live.hand_radius_m;
  return options;
}

}  // namespace

struct SimNode::Impl {
  Impl(const OfflineOptions& shared_options, const LiveOptions& live_options, bus::Participant& dds)
      : shared(shared_options), live(live_options), options(live_session_options(shared, live)),
        session(options), replayed((session.set_shapes(shared.spheres, shared.ground), replay_journal())), strokes(dds, bus::topics::stroke),
        topology_writer(dds, bus::topics::cloth_topology), state_writer(dds, bus::topics::cloth_state),
        cut_writer(dds, bus::topics::cut_event), heartbeat(dds, "tachi-sim"),
        // Each run is a new session: readers follow it even though its topology version starts again.
        session_id(bus::new_session_id()),
        guard([this](std::string_view reason) {
          heartbeat.count_rejected(reason);
          if (++rejected == 1 || rejected % 100 == 0)
            spdlog::warn("tachi-sim: {} hand samples rejected (last: {})", rejected, reason);
        }),
        delta_writer((topology_first(), dds), bus::topics::cloth_topology_delta), delta(session.cloth()),
        rate(Clock::now()), schedule(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.solver.dt)),
                                     Clock::now()),
        start(Clock::now()), waiting_for_filter("tachi-filter", dds.domain()) {
    if (live.exit_when_idle_s > 0) {
      idle_end.emplace(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(live.exit_when_idle_s)), start);
      // A simulator restarted late in a run has had its hand samples (the replayed journal): idle counts too.
      if (replayed_samples > 0) idle_end->hand_sample(start);
      try {
        statuses.emplace(dds, bus::topics::node_status, bus::ReaderKind::Observer);
      } catch (const bus::DdsError& e) {
        // A PKI made before the sim's grant included the heartbeats: the run still ends, without the hold.
        spdlog::warn("tachi-sim: {}; a restarted sensor or filter will not hold the run's end (scripts/make_test_pki.sh "
                     "grants it)", e.what());
      }
    }

    if (session.object() != nullptr) {
      // Transient-local: a viewer that starts later still gets the object it should draw.
      object_writer.emplace(dds, bus::topics::scene_object);
      object_writer->write(object.fill(live.cloth_id, session.object()->points(), session_id));
    }
    heartbeat.set_metric("blade", static_cast<double>(to_msg(shared.blade)));  // tachi.idl's Blade: the viewer's HUD names it
  }

  /// No lost cuts: replay what a previous run of this journal applied, then append to it.
  ReplayedSamples replay_journal() {
    if (live.journal.empty()) return {};
    const auto t0 = Clock::now();
    journal.emplace(live.journal, journal_fingerprint(options));
    ReplayedSamples applied{replay(journal->recovered(), session)};
    for (const auto& record : journal->recovered()) replayed_samples += record.kind == JournalRecord::Kind::Hand ? 1 : 0;
    (void)session.take_cut_reports();      // the previous run reported them
    (void)session.take_topology_change();  // published whole below
    spdlog::info("tachi-sim: replayed {} journal records ({} steps, {} cut particles) from {} in {:.0f} ms",
                 journal->recovered().size(), session.steps(), session.cutter().total().particles_duplicated,
                 live.journal, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    return applied;
  }

  /// The whole topology goes out before the delta writer exists, as the first thing a reader sees.
  void topology_first() {
    topology.fill(live.cloth_id, session.cloth(), nullptr, session_id);
    topology_writer.write(topology.msg());
  }

  void journal_append(const JournalRecord& record) {
    if (!journal) return;
    const bool was_full = journal->full();
    if (!journal->append(record) && !was_full)
      spdlog::error("tachi-sim: journal {} is full ({} MB); later samples are not journaled", journal->path().string(),
                    Journal::kMaxBytes >> 20);  // tachi-sim uses the default bound
  }

  // Topology changes and closed strokes go out before the state that indexes the new topology, the changes as
  // deltas at the bounded rate of TopologyRate. False while a change waits for a token: a state
  // published then would index a topology no reader has yet.
  bool publish_changes() {
    const auto now = Clock::now();
    bool in_sync = !session.topology_changed();
    if (!in_sync && rate.delta_allowed(now)) {
      if (const auto change = session.take_topology_change()) {
        delta.fill(live.cloth_id, session.cloth(), *change, session_id);
        delta_writer.write(delta.msg());
        ++messages_out;
        ++topology_updates;
        topology_bytes += delta.payload_bytes();
        rate.delta_sent();
      }
      in_sync = true;
    }
    if (rate.take_keyframe(now)) {
      topology.fill(live.cloth_id, session.cloth(), nullptr, session_id);
      topology_writer.write(topology.msg());
      ++messages_out;
    }
    for (const auto& report : session.take_cut_reports()) {
      cut_writer.write(cut_msg(live.cloth_id, session.cloth().topology_version, report, cut_line, session_id));
      ++messages_out;
      spdlog::info("tachi-sim: stroke {} cut {} particles over {:.3f} m; {} pieces, {} falling", report.stroke_id,
                   report.stroke.particles_duplicated, report.stroke.cut_length_m, report.pieces, report.fallen_pieces);
      heartbeat.set_metric("pieces", static_cast<double>(report.pieces));
      heartbeat.set_metric("fallen_pieces", static_cast<double>(report.fallen_pieces));
      cut_length_m += report.stroke.cut_length_m;
    }
    return in_sync;
  }

  std::int64_t publish_state() {
    auto msg = state_msg(live.cloth_id, session.steps(), session.time_s(), session.cloth(), session_id, session.held_particle());
    msg.acquired_ns = newest_acquired_ns;
    msg.published_ns = common::wall_clock_ns();
    state_writer.write(msg);
    ++messages_out;
    return msg.published_ns;
  }

  /// Applies the stroke samples that arrived; the newest acquired_ns among them (0: none applied).
  std::int64_t apply_strokes() {
    std::int64_t batch_acquired_ns = 0;
    for (const auto& sample : strokes.take()) {
      const auto input = from_msg(*sample);
      if (!input) {
        const auto& p = sample->position_m;  // refused for being non-finite, or > 100 m from the cloth
        guard.reject(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) ? "out_of_range" : "nonfinite");
        continue;
      }
      // Re-delivered by the filter's history after a restart, and already replayed from the journal.
      if (replayed.already_applied(input->sensor_id, input->session_id, sample->time_ns)) continue;
      // A stroke is (sensor, filter session, stroke id): its samples' times never go back.
      // ... and its stroke ids never go back: a lower id names a stroke that already ended.
      // (A far-future stamp or id is refused, and never locks the stroke out for more than the skew.)
      const auto now_ns = bus::InputGuard::now_ns();
      if (!guard.time(input->session_id ^ input->sensor_id, sample->time_ns, now_ns) ||
          !guard.id(input->session_id ^ input->sensor_id, input->stroke_id, now_ns))
        continue;
      const HandInput hand{input->stroke_id, input->time_s,  input->position_m, input->tracked,
                           input->cutting,   input->holding, input->session_id, input->sensor_id,
                           input->grabbing};
      const auto held_before = session.held_particle();
      session.on_hand(hand);
      if (grace.on_sample(hand.session_id, hand.cutting) == StrokePublisherGrace::Verdict::PublisherBack)
        spdlog::info("tachi-sim: the stroke's publisher is back (session {:x}); the stroke goes on", hand.session_id);
      if (session.held_particle() != held_before) {
        if (session.held_particle()) spdlog::info("tachi-sim: the hand took particle {}", *session.held_particle());
        else spdlog::info("tachi-sim: the hand let go of particle {}", *held_before);
      }
      if (const auto why = session.take_grab_refusal()) {
        spdlog::warn("tachi-sim: {}", *why);
        ++grabs_refused;
      }
      journal_append({JournalRecord::Kind::Hand, session.steps(), input->sensor_id, sample->time_ns, hand});
      ++samples_in;
      if (idle_end) idle_end->hand_sample(Clock::now());
      batch_acquired_ns = std::max(batch_acquired_ns, sample->acquired_ns);
    }
    return batch_acquired_ns;
  }

  /// The hand sources' heartbeats: a sensor or filter the launcher restarted is starting (replaying its
  /// recording or journal), and the run must not end in the gap before it publishes again.
  void watch_hand_sources() {
    if (!statuses) return;
    const auto now = Clock::now();
    for (const auto& status : statuses->take()) {
      const std::string node(status->node);
      if (node == "tachi-sensor" || node == "tachi-filter")
        idle_end->source_status(node, status->state == tachi_msg_NODE_STARTING, now);
    }
  }

  /// A filter that vanished mid-stroke would leave the stroke open forever: close it, unless it comes back.
  void watch_stroke_publisher() {
    const bool has_filter = strokes.matched_writers() > 0;
    waiting_for_filter.warn_if_waiting(has_filter);
    switch (grace.tick(has_filter, session.cutter().stroke_open(), Clock::now())) {
      case StrokePublisherGrace::Verdict::PublisherGone:
        spdlog::warn("tachi-sim: the stroke publisher went away mid-stroke; closing the stroke unless it is back within {} s",
                     std::chrono::duration_cast<std::chrono::seconds>(grace.grace()).count());
        break;
      case StrokePublisherGrace::Verdict::CloseStroke:
        spdlog::warn("tachi-sim: the stroke publisher did not come back; the stroke is closed");
        session.end_stroke();
        journal_append({JournalRecord::Kind::EndStroke, session.steps(), 0, 0, {}});
        break;
      default: break;
    }
  }

  bool spin_once() {
    strokes.wait_for_data(schedule.until_next(Clock::now()));
    // A stroke sample is applied as soon as it arrives (the waitset woke us), and the state that
    // reflects it goes out now rather than at the next 60 Hz step: capture -> state latency.
    if (const std::int64_t batch_acquired_ns = apply_strokes(); batch_acquired_ns > 0) {
      newest_acquired_ns = batch_acquired_ns;
      if (publish_changes()) latency.add_since(batch_acquired_ns, publish_state());
      else if (pending_latency_ns == 0) pending_latency_ns = batch_acquired_ns;
      heartbeat.set_metric("latency_p50_ms", latency.percentile(50));
      heartbeat.set_metric("latency_p99_ms", latency.percentile(99));
    }
    watch_stroke_publisher();
    if (journal) journal->flush();

    if (schedule.due(Clock::now())) {
      const auto before = Clock::now();
      session.step();
      step_ms.add_ms(std::chrono::duration<double, std::milli>(Clock::now() - before).count());
      schedule.stepped(Clock::now());
      const bool in_sync = publish_changes();
      if (in_sync && session.steps() % static_cast<std::uint64_t>(live.state_every) == 0) {
        const std::int64_t published_ns = publish_state();
        // A cutting sample whose delta waited for a token is reflected by this state: its latency counts here.
        if (pending_latency_ns > 0) latency.add_since(pending_latency_ns, published_ns);
        pending_latency_ns = 0;
      }
      heartbeat.set_metric("strokes", static_cast<double>(session.strokes()));  // received, whatever their source
      heartbeat.set_metric("cuts", static_cast<double>(session.cuts()));  // strokes that cut, the open one included
      heartbeat.set_metric("cut_length_m", cut_length_m);
      heartbeat.set_metric("steps", static_cast<double>(session.steps()));
      // Degraded says why: the solver fell behind real time.
      heartbeat.update(schedule.overruns() > 0 ? tachi_msg_NODE_DEGRADED : tachi_msg_NODE_RUNNING, samples_in, messages_out,
                       (schedule.overruns() > 0 ? std::to_string(schedule.overruns()) + " steps overran their real-time slot; "
                                                : std::string()) +
                           "steps " + std::to_string(session.steps()));
    }
    if (live.max_steps && session.steps() >= static_cast<std::uint64_t>(*live.max_steps)) return false;
    if (live.duration_s > 0 && Clock::now() - start > std::chrono::duration<double>(live.duration_s)) return false;
    if (idle_end) {
      watch_hand_sources();
      if (idle_end->over(Clock::now())) return false;
    }
    return true;
  }

  int finish() {
    session.end_stroke();
    if (journal) {
      journal_append({JournalRecord::Kind::EndStroke, session.steps(), 0, 0, {}});
      journal->flush();
    }
    if (const auto change = session.take_topology_change()) {
      delta.fill(live.cloth_id, session.cloth(), *change, session_id);
      delta_writer.write(delta.msg());
      rate.final_delta_sent();
    }
    if (rate.keyframe_owed()) {
      topology.fill(live.cloth_id, session.cloth(), nullptr, session_id);
      topology_writer.write(topology.msg());
    }
    for (const auto& report : session.take_cut_reports())
      cut_writer.write(cut_msg(live.cloth_id, session.cloth().topology_version, report, cut_line, session_id));
    publish_state();
    // Let late readers (viewer, tests) receive the final topology and cuts before the process goes: one
    // deadline for the three. Stopped by a signal (the whole run stopping, or the launcher's death) the
    // readers are going too and their acks may never come: then only a glimpse, so that the process is
    // gone within a second (docs/reliability.md, Signals).
    const auto acks_due = Clock::now() + (common::stop_requested() ? std::chrono::milliseconds(100) : std::chrono::milliseconds(1000));
    const auto left = [&] { return std::max<Clock::duration>(acks_due - Clock::now(), Clock::duration::zero()); };
    topology_writer.wait_for_acks(left());
    delta_writer.wait_for_acks(left());
    cut_writer.wait_for_acks(left());

    Summary summary = summarize(session.cloth());
    summary.steps = static_cast<int>(session.steps());
    add_cut_summary(summary, session.cloth(), session.cutter());
    add_session_summary(summary, session);
    add_step_times(summary, step_ms);
    summary.extra["hand_samples"] = samples_in + replayed_samples;  // the run's, across restarts
    summary.extra["hand_samples_rejected"] = rejected;
    summary.extra["step_overruns"] = schedule.overruns();
    summary.extra["grabs_refused"] = grabs_refused;
    summary.extra["topology_updates"] = topology_updates;
    summary.extra["topology_bytes_per_update"] = topology_updates > 0 ? topology_bytes / topology_updates : 0;
    summary.extra["topology_keyframe_bytes"] = topology.payload_bytes();
    summary.extra["latency_p50_ms"] = latency.percentile(50);
    summary.extra["latency_p99_ms"] = latency.percentile(99);
    summary.extra["latency_ms"] = latency.values();  // capture -> published state per depth frame (the last 1024)
    spdlog::info("tachi-sim: stopped after {} steps ({} hand samples, {} pieces)", summary.steps, samples_in, summary.pieces);
    if (!shared.export_dir.empty()) export_run(summary, session.cloth(), shared.export_dir, &session.cutter());
    return common::kExitOk;
  }

  const OfflineOptions shared;
  const LiveOptions live;
  const SessionOptions options;
  Session session;
  std::optional<Journal> journal;
  std::uint64_t replayed_samples = 0;  // hand samples a previous run of this journal applied (set by replay_journal)
  ReplayedSamples replayed;            // initialised by replay_journal(): declared after what it sets
  bus::Reader<tachi_msg_StrokeSample> strokes;
  bus::Writer<tachi_msg_ClothTopology> topology_writer;
  bus::Writer<tachi_msg_ClothState> state_writer;
  bus::Writer<tachi_msg_CutEvent> cut_writer;
  bus::Heartbeat heartbeat;
  const std::uint64_t session_id;
  std::uint64_t rejected = 0;
  bus::InputGuard guard;
  TopologyMessage topology;
  bus::Writer<tachi_msg_ClothTopologyDelta> delta_writer;
  TopologyDeltaMessage delta;
  TopologyRate rate;
  StepSchedule schedule;
  StrokePublisherGrace grace;
  std::vector<tachi_msg_GridCoord> cut_line;
  ObjectMessage object;
  std::optional<bus::Writer<tachi_msg_SceneObject>> object_writer;
  const Clock::time_point start;
  std::optional<IdleEnd> idle_end;                            // with --exit-when-idle
  std::optional<bus::Reader<tachi_msg_NodeStatus>> statuses;  // ... the hand sources' heartbeats
  std::uint64_t samples_in = 0, messages_out = 1, grabs_refused = 0;
  std::uint64_t topology_updates = 0;
  std::size_t topology_bytes = 0;
  double cut_length_m = 0.0;
  common::DurationHistogram step_ms;  // every step of the run, in constant memory
  // acquired_ns of the newest applied hand sample: every state published from then on reflects it.
  std::int64_t newest_acquired_ns = 0;
  std::int64_t pending_latency_ns = 0;  // oldest applied sample whose state waits for its topology delta
  common::LatencyWindow latency;
  common::PeerWait waiting_for_filter;
};

SimNode::SimNode(const OfflineOptions& shared, const LiveOptions& live, bus::Participant& dds)
    : impl_(std::make_unique<Impl>(shared, live, dds)) {}
SimNode::~SimNode() = default;
bool SimNode::spin_once() { return impl_->spin_once(); }
int SimNode::finish() { return impl_->finish(); }

}  // namespace tachi::sim
