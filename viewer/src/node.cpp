#include "tachi/viewer/node.hpp"

#include "bus_adapter.hpp"
#include "tachi/bus/blade.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/viewer/frame_stats.hpp"
#include "tachi/viewer/outputs.hpp"

#include <spdlog/spdlog.h>

#include <random>
#include <string_view>

namespace tachi::viewer {
namespace {
using namespace std::chrono_literals;

// An object's point cloud is drawn as at most this many dots (evenly thinned): enough to see its shape.
constexpr std::size_t kMaxObjectDots = 20000;

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::uint64_t random_session_id() {
  std::random_device device;
  return (std::uint64_t{device()} << 32) | device();
}

// The blade the simulator cuts with (seed 001 Figure 4), from its heartbeat's "blade" figure.
std::optional<std::string> blade_of(const tachi_msg_NodeStatus& status) {
  if (std::string_view(status.node) != "tachi-sim") return std::nullopt;
  for (std::uint32_t i = 0; i < status.metrics._length; ++i) {
    const auto& metric = status.metrics._buffer[i];
    if (std::string_view(metric.name) != "blade") continue;
    if (const auto name = bus::blade_name(metric.value)) return std::string(*name);
  }
  return std::nullopt;
}

void fill_hud(Hud& hud, const SceneState& state, const FrameStats& stats, const std::string& blade, std::uint64_t rejected,
              const std::string& warning) {
  hud.fps = stats.fps();
  hud.state_age_ms = stats.latest_age_ms();
  hud.gate = state.gate();
  hud.blade = blade;
  hud.columns = state.columns();
  hud.rows = state.rows();
  hud.topology_version = state.scene().mesh.topology_version;
  hud.pieces = state.pieces();
  hud.fallen_pieces = state.fallen_pieces();
  hud.rejected = rejected;
  hud.warning = warning;
}

View initial_view(const ViewerOptions& o, ViewerWindow* display) {
  View view;
  view.width = view.height = o.size;
  if (display) {
    const cv::Size size = display->image_size();
    view.width = size.width;
    view.height = size.height;
  }
  return view;
}
}  // namespace

std::string participant_identity(const ViewerOptions& options) {
  return options.mouse && options.bus.identity == "viewer" ? "mouse" : options.bus.identity;
}

struct ViewerNode::Impl {
  Impl(const ViewerOptions& o, bus::Participant& dds, ViewerWindow* display_)
      : options(o), display(display_), topologies(dds, bus::topics::cloth_topology),
        topology_deltas(dds, bus::topics::cloth_topology_delta), states(dds, bus::topics::cloth_state),
        strokes(dds, bus::topics::stroke), cuts(dds, bus::topics::cut_event), statuses(dds, bus::topics::node_status),
        objects(dds, bus::topics::scene_object), waitset(dds), heartbeat(dds, "tachi-viewer"),
        // Boundary checks (sizes, consistent arrays) before a message is copied; SceneState then checks
        // versions, sessions and coordinates (docs/viewer.md). Both count in the heartbeat.
        guard([this](std::string_view reason) {
          heartbeat.count_rejected(reason);
          spdlog::warn("tachi-viewer: cloth message rejected ({})", reason);
        }),
        mouse_source{o.mouse_sensor_id, random_session_id()}, start(Clock::now()), frames(o.fps, start),
        blade_hold(start), cloth_watch(o.bus.domain, start), limits{o.duration_s, o.exit_when_idle_s},
        view(initial_view(o, display)), home(view),
        outputs(o, cv::Size(view.width, view.height)), mouse(o.mouse) {
    if (o.mouse) blade_writer.emplace(dds, bus::topics::stroke);
    if (o.mouse && display) display->hide_pointer();
    waitset.attach(topologies);
    waitset.attach(topology_deltas);
    waitset.attach(states);
    waitset.attach(strokes);
    waitset.attach(cuts);
    if (o.mouse)
      spdlog::info("tachi-viewer: mouse blade publishes as sensor {} (session {:016x}); hold the left button to cut",
                   mouse_source.sensor_id, mouse_source.session_id);
    if (!display && !outputs.any())
      spdlog::warn("tachi-viewer: --headless without --video, --snapshot or --frames-dir: nothing will be written");
  }

  void publish(const std::optional<BladeSample>& sample) {
    if (!sample) return;
    blade_writer->write(to_msg(*sample, mouse_source, mouse.samples(), wall_ns()));
    blade_hold.sent(Clock::now());
    ++messages_out;
  }

  void count(std::optional<Rejection> rejected) {
    if (rejected) heartbeat.count_rejected(to_string(*rejected));
  }

  double seconds(Clock::time_point t) const { return std::chrono::duration<double>(t - start).count(); }

  // The window's keys and mouse; false when the user quit.
  bool window_input() {
    waitset.wait(std::min(frames.wait(Clock::now()), Clock::duration(4ms)));
    const int key = display->poll(1);
    if (!display->open()) return false;
    switch (on_key(key, view, home)) {
      case KeyAction::Quit: return false;
      case KeyAction::Snapshot: outputs.snapshot_now(); break;
      case KeyAction::ToggleHelp: state.scene().show_help = !state.scene().show_help; break;
      case KeyAction::ViewChanged:
      case KeyAction::None: break;
    }
    for (const auto& event : display->take_mouse_events()) publish(mouse.on_event(event, state.scene().mesh, view));
    if (blade_hold.due(Clock::now())) publish(mouse.hold(state.scene().mesh, view));
    return true;
  }

  void take_bus() {
    // A keyframe the scene refuses (a version jump, indices out of range) must not become the base the
    // deltas apply to either: the scene judges it first.
    bool topology_changed = false;
    for (const auto& t : topologies.take()) {
      ++messages_in;
      if (!plausible(*t, guard)) continue;
      const auto rejected = state.on_topology(from_msg(*t));
      count(rejected);
      if (!rejected) topology.on_keyframe(*t);
    }
    for (const auto& d : topology_deltas.take()) {
      ++messages_in;
      topology_changed = topology.on_delta(*d) || topology_changed;
    }
    if (topology_changed) count(state.on_topology(from_assembler(topology)));
    for (const auto& s : states.take(8)) {
      ++messages_in;
      if (!plausible(*s, guard)) continue;
      const auto rejected = state.on_state(from_msg(*s));
      count(rejected);
      if (!rejected) cloth_watch.state_arrived(Clock::now());
    }
    for (const auto& h : strokes.take()) {
      state.on_hand(from_msg(*h));
      ++messages_in;
    }
    for (const auto& c : cuts.take()) {
      count(state.on_cut(from_msg(*c), seconds(Clock::now())));
      ++messages_in;
    }
    for (const auto& s : statuses.take())
      if (const auto blade = blade_of(*s)) sim_blade = *blade;
    for (const auto& obj : objects.take()) {
      ++messages_in;
      if (auto points = object_points(*obj, guard, kMaxObjectDots)) state.scene().object_points = std::move(*points);
    }
  }

  void render_frame(Clock::time_point now, const std::string& warning) {
    if (display) {
      const cv::Size size = display->image_size();
      view.width = size.width;
      view.height = size.height;
    }
    // The stage's latency is capture -> the first frame that shows a new hand sample; once the hand
    // stops, the shown state's age keeps growing (the HUD shows it) but is no delay of this viewer.
    std::optional<double> age_ms;
    if (state.shown_acquired_ns() > 0) age_ms = static_cast<double>(wall_ns() - state.shown_acquired_ns()) * 1e-6;
    const bool new_sample_shown = state.shown_acquired_ns() > 0 && state.shown_acquired_ns() != counted_acquired_ns;
    stats.frame(now, new_sample_shown ? age_ms : std::nullopt);
    if (new_sample_shown) counted_acquired_ns = state.shown_acquired_ns();
    state.advance(seconds(now));
    Scene& scene = state.scene();
    if (!scene.hud) scene.hud.emplace();
    fill_hud(*scene.hud, state, stats, mouse.label().empty() ? sim_blade : sim_blade + " " + mouse.label(),
             heartbeat.rejected(), warning);
    scene.blade = mouse.cursor();
    image = render(scene, view);
    outputs.frame(image, now);
    if (display) display->show(image);
    heartbeat.set_metric("fps", stats.fps());
    heartbeat.set_metric("frames", static_cast<double>(stats.frames()));
    if (const auto p50 = stats.age_ms(0.5)) heartbeat.set_metric("state_age_p50_ms", *p50);
    if (const auto p99 = stats.age_ms(0.99)) heartbeat.set_metric("state_age_p99_ms", *p99);
    heartbeat.set_metric("mouse_samples", static_cast<double>(mouse.samples()));
  }

  bool spin_once() {
    if (display) {
      if (!window_input()) return false;
    } else {
      waitset.wait(frames.wait(Clock::now()));
    }
    take_bus();
    const auto now = Clock::now();
    const std::string warning = cloth_watch.warning(now);
    if (cloth_watch.log_due(now)) spdlog::warn("tachi-viewer: {}", warning);
    // Degraded says why (the warning); running says what it waits for, if anything.
    heartbeat.update(warning.empty() ? tachi_msg_NODE_RUNNING : tachi_msg_NODE_DEGRADED, messages_in,
                     messages_out + stats.frames(),
                     !warning.empty() ? warning : state.has_cloth() ? "" : "waiting for the cloth");
    if (frames.due(now)) render_frame(now, warning);
    return !limits.over(now - start, state.states_received(), cloth_watch.without_state(now));
  }

  int finish() {
    if (const auto last = mouse.finish(state.scene().mesh, view)) {
      publish(last);
      blade_writer->wait_for_acks(300ms);  // the simulator closes the stroke; stopping stays within 1 s
    }
    if (image.empty()) image = render(state.scene(), view);
    outputs.finish(image);
    spdlog::info("tachi-viewer: {} frames rendered, {} cloth states received, {} inputs rejected", stats.frames(),
                 state.states_received(), heartbeat.rejected());
    return common::kExitOk;
  }

  const ViewerOptions& options;
  ViewerWindow* display;
  bus::Reader<tachi_msg_ClothTopology> topologies;
  // Keyframes + deltas -> the current topology, the one way every reader assembles it.
  bus::Reader<tachi_msg_ClothTopologyDelta> topology_deltas;
  bus::TopologyAssembler topology;
  bus::Reader<tachi_msg_ClothState> states;
  bus::Reader<tachi_msg_StrokeSample> strokes;
  bus::Reader<tachi_msg_CutEvent> cuts;
  bus::Reader<tachi_msg_NodeStatus> statuses;
  bus::Reader<tachi_msg_SceneObject> objects;  // what the cloth drapes over
  std::optional<bus::Writer<tachi_msg_StrokeSample>> blade_writer;
  bus::WaitSet waitset;
  bus::Heartbeat heartbeat;
  bus::InputGuard guard;
  MouseSource mouse_source;
  Clock::time_point start;
  FrameSchedule frames;
  BladeHold blade_hold;
  ClothWatch cloth_watch;
  RunLimits limits;
  View view;
  View home;
  Outputs outputs;
  MouseControl mouse;
  SceneState state;
  FrameStats stats;
  std::int64_t counted_acquired_ns = 0;  // acquired_ns whose first showing the stats counted
  std::string sim_blade = "-";
  std::uint64_t messages_in = 0;
  std::uint64_t messages_out = 0;
  cv::Mat image;
};

ViewerNode::ViewerNode(const ViewerOptions& options, bus::Participant& dds, ViewerWindow* display)
    : impl_(std::make_unique<Impl>(options, dds, display)) {}
ViewerNode::~ViewerNode() = default;
bool ViewerNode::spin_once() { return impl_->spin_once(); }
int ViewerNode::finish() { return impl_->finish(); }

}  // namespace tachi::viewer
