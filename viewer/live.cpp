#include "live.hpp"

#include "src/bus_adapter.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/blade.hpp"
#include "tachi/viewer/controls.hpp"
#include "tachi/viewer/frame_stats.hpp"
#include "tachi/viewer/mesh_file.hpp"
#include "window.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>

namespace tachi::viewer {
namespace {
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

// Headless, a missing cloth is said this often; in a window the HUD says it after this long.
constexpr auto kNoStateWarningPeriod = 5s;
constexpr auto kNoStateHudAfter = 3s;
const std::string kWindowName = "tachi";
// A held, unmoving blade repeats its sample this often (tachi-sim lets another source take over after 1 s).
constexpr auto kBladeHoldPeriod = 250ms;
// An object's point cloud is drawn as at most this many dots (evenly thinned): enough to see its shape.
constexpr std::size_t kMaxObjectDots = 20000;

const CLI::Validator kVideoFile(
    [](std::string& path) {
      const auto ext = std::filesystem::path(path).extension().string();
      return ext == ".mp4" || ext == ".avi" ? std::string() : "'" + path + "' must end in .mp4 or .avi";
    },
    "FILE.mp4|FILE.avi");

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write image " + path);
}

// .mp4 as H.264 (what browsers and phones play) when this FFmpeg can encode it, else MPEG-4 part 2;
// .avi as Motion JPEG.
cv::VideoWriter open_video(const std::string& path, double fps, cv::Size size) {
  cv::VideoWriter writer;
  if (std::filesystem::path(path).extension() == ".avi") {
    writer.open(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size);
  } else {
    for (const auto& codec : {"avc1", "mp4v"})
      if (writer.open(path, cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]), fps, size)) break;
  }
  if (!writer.isOpened()) throw std::runtime_error("--video: cannot open " + path + " for writing");
  return writer;
}

// Everything that turns frames into files: --video, --frames-dir, --snapshot and the `p` key.
class Outputs {
 public:
  Outputs(const ViewerOptions& o, cv::Size size) : options_(o) {
    if (!o.frames_dir.empty()) std::filesystem::create_directories(o.frames_dir);
    if (!o.video.empty()) video_ = open_video(o.video, o.fps, size);
    video_size_ = size;
  }
  /// One rendered frame, shown at `now`. The video's time stamps are its frame numbers over --fps, so
  /// a frame is written as many times as --fps frames fit since the first one: a viewer that renders
  /// slower than --fps (a busy machine) makes a video that still plays at the speed the run went.
  void frame(const cv::Mat& image, Clock::time_point now) {
    last_ = image;
    if (!options_.frames_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05llu.png", static_cast<unsigned long long>(frames_));
      write_image((std::filesystem::path(options_.frames_dir) / name).string(), image);
    }
    if (video_.isOpened()) {
      if (!video_start_) video_start_ = now;
      const double t = std::chrono::duration<double>(now - *video_start_).count();
      // Frame k shows time k / fps: this image stands for every slot up to now (a frame rendered early,
      // before its slot, waits for the next call rather than running the video ahead).
      const auto due = static_cast<std::uint64_t>(std::floor(t * options_.fps + 1e-6)) + 1;
      if (due > video_frames_) {
        // A video keeps one frame size: a resized window is scaled to it.
        cv::Mat scaled;
        if (image.size() != video_size_) cv::resize(image, scaled, video_size_, 0, 0, cv::INTER_AREA);
        const cv::Mat& written = scaled.empty() ? image : scaled;
        for (; video_frames_ < due; ++video_frames_) video_.write(written);
      }
    }
    ++frames_;
  }
  void snapshot_now() {
    if (last_.empty()) return;
    std::filesystem::create_directories(options_.snapshot_dir);
    const auto path = std::filesystem::path(options_.snapshot_dir) / ("tachi_snapshot_" + std::to_string(++snapshots_) + ".png");
    write_image(path.string(), last_);
    spdlog::info("tachi-viewer: snapshot saved to {}", path.string());
  }
  void finish(const cv::Mat& last) {
    if (!options_.snapshot.empty()) write_image(options_.snapshot, last);
    if (video_.isOpened()) {
      video_.release();
      spdlog::info("tachi-viewer: {} frames rendered, {} video frames at {} fps written to {}", frames_, video_frames_,
                   options_.fps, options_.video);
    }
  }
  bool any() const { return !options_.snapshot.empty() || !options_.frames_dir.empty() || !options_.video.empty(); }

 private:
  const ViewerOptions& options_;
  cv::VideoWriter video_;
  cv::Size video_size_;
  cv::Mat last_;
  std::uint64_t frames_ = 0;
  std::optional<Clock::time_point> video_start_;
  std::uint64_t video_frames_ = 0;
  unsigned snapshots_ = 0;
};

std::uint64_t random_session_id() {
  std::random_device device;
  return (std::uint64_t{device()} << 32) | device();
}

// The window's mouse: orbit/pan/zoom the view, or (with --mouse) cut with the left button.
class MouseControl {
 public:
  MouseControl(bool blade, MouseSource source) : blade_enabled_(blade), source_(source) {}

  /// Applies one event; returns the blade sample to publish, if any.
  std::optional<tachi_msg_StrokeSample> on_event(const MouseEvent& e, const Mesh& mesh, View& view) {
    std::optional<BladeSample> sample;
    switch (e.kind) {
      case MouseEvent::LeftDown:
        if (blade_enabled_) sample = blade_.press(mesh, view, e.pixel);
        else drag_ = Drag::Orbit;
        break;
      case MouseEvent::RightDown: drag_ = blade_enabled_ && !e.shift ? Drag::Orbit : Drag::Pan; break;
      case MouseEvent::LeftUp:
        if (blade_enabled_) sample = blade_.release(mesh, view, e.pixel);
        drag_ = Drag::None;
        break;
      case MouseEvent::RightUp: drag_ = Drag::None; break;
      case MouseEvent::Wheel: view.zoom(e.wheel > 0 ? 1.15f : 1.0f / 1.15f); break;
      case MouseEvent::Move:
        if (blade_enabled_) sample = blade_.move(mesh, view, e.pixel);
        if (drag_ == Drag::Orbit) orbit_by_drag(view, e.pixel.x - last_.x, e.pixel.y - last_.y);
        if (drag_ == Drag::Pan) view.pan(e.pixel.x - last_.x, e.pixel.y - last_.y);
        break;
    }
    last_ = e.pixel;
    if (!sample) return std::nullopt;
    ++samples_;
    return to_msg(*sample, source_, samples_, wall_ns());
  }
  /// While the button is held still, the same spot again (re-cast: the cloth moves under it), so the
  /// simulator does not take the mouse for a source that fell silent mid-stroke.
  std::optional<tachi_msg_StrokeSample> hold(const Mesh& mesh, const View& view) {
    if (const auto sample = blade_.move(mesh, view, last_)) return to_msg(*sample, source_, ++samples_, wall_ns());
    return std::nullopt;
  }
  /// The sample that ends a stroke still open when the viewer stops.
  std::optional<tachi_msg_StrokeSample> finish(const Mesh& mesh, const View& view) {
    if (const auto sample = blade_.release(mesh, view, last_)) return to_msg(*sample, source_, ++samples_, wall_ns());
    return std::nullopt;
  }
  std::optional<BladeCursor> cursor() const {
    if (!blade_enabled_ || last_.x < 0.0f) return std::nullopt;
    return BladeCursor{last_, blade_.cutting()};
  }
  std::string label() const { return blade_enabled_ ? (blade_.cutting() ? "(mouse, cutting)" : "(mouse)") : ""; }
  std::uint64_t samples() const { return samples_; }

 private:
  enum class Drag { None, Orbit, Pan };
  bool blade_enabled_;
  MouseSource source_;
  MouseBlade blade_;
  Drag drag_ = Drag::None;
  cv::Point2f last_{-1.0f, -1.0f};
  std::uint64_t samples_ = 0;
};

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

void fill_hud(Hud& hud, const SceneState& state, const FrameStats& stats, std::optional<double> age_ms,
              const std::string& blade, std::uint64_t rejected, const std::string& warning) {
  hud.fps = stats.fps();
  hud.state_age_ms = age_ms;
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
}  // namespace

void add_viewer_flags(CLI::App& app, ViewerOptions& o) {
  common::add_bus_flags(app, o.bus);
  auto* headless = app.add_flag("--headless", o.headless, "No window: render off-screen (use with --video, --snapshot or --frames-dir)");
  app.add_option("--snapshot", o.snapshot, "Write the last rendered frame to this PNG when the viewer stops");
  app.add_option("--snapshot-dir", o.snapshot_dir, "Folder for the snapshots the `p` key saves")->capture_default_str();
  auto* frames = app.add_option("--frames-dir", o.frames_dir, "Write every rendered frame as DIR/frame_NNNNN.png");
  auto* video = app.add_option("--video", o.video, "Write the rendered frames as a video (.mp4: H.264 or MPEG-4; .avi: MJPG)")
                    ->check(kVideoFile);
  auto* mouse = app.add_flag("--mouse", o.mouse,
                             "Seed 001's blade: the cursor cuts the cloth while the left button is held (publishes on "
                             "tachi/hand/stroke as its own hand source)")
                    ->excludes(headless);
  app.add_option("--mouse-sensor-id", o.mouse_sensor_id, "sensor_id of the mouse blade's stroke samples")
      ->needs(mouse)
      ->capture_default_str();
  app.add_option("--mesh", o.mesh, "Offline view of an exported OBJ (tachi-sim --export's cloth.obj; pieces in shades), no DDS")
      ->check(CLI::ExistingFile)
      ->excludes(mouse)
      ->excludes(video)
      ->excludes(frames);
  app.add_option("--fps", o.fps, "Frames rendered per second")
      ->check(CLI::Range(1.0, 240.0))
      ->capture_default_str();
  app.add_option("--size", o.size, "Image width and height in pixels (a window is shrunk to fit the screen)")
      ->check(CLI::Range(64, 4096))
      ->capture_default_str();
  app.add_option("--duration", o.duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM or q)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--exit-when-idle", o.exit_when_idle_s,
                 "Stop when no cloth state arrived for this many seconds after the first one (0: never)")
      ->check(CLI::Range(0.0, 1e7));
}

int run_live(const ViewerOptions& o) {
  if (!o.headless && std::getenv("DISPLAY") == nullptr)
    throw std::runtime_error("no display (DISPLAY is not set); use --headless with --video, --snapshot or --frames-dir");

  // DDS Security (issue 13): the viewer's grant may not publish strokes; the mouse blade is the
  // "mouse" identity, whose grant adds tachi/hand/stroke (scripts/make_test_pki.sh).
  const std::string identity = o.mouse && o.bus.identity == "viewer" ? "mouse" : o.bus.identity;
  bus::Participant dds{o.bus.domain, o.bus.dds_config, {o.bus.secure_dir, identity}};
  bus::Reader<tachi_msg_ClothTopology> topologies{dds, bus::topics::cloth_topology};
  // Issue 11: keyframes + deltas -> the current topology, the one way every reader assembles it.
  bus::Reader<tachi_msg_ClothTopologyDelta> topology_deltas{dds, bus::topics::cloth_topology_delta};
  bus::TopologyAssembler topology;
  bus::Reader<tachi_msg_ClothState> states{dds, bus::topics::cloth_state};
  bus::Reader<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_CutEvent> cuts{dds, bus::topics::cut_event};
  bus::Reader<tachi_msg_NodeStatus> statuses{dds, bus::topics::node_status};
  bus::Reader<tachi_msg_SceneObject> objects{dds, bus::topics::scene_object};  // issue 12: what the cloth drapes over
  std::optional<bus::Writer<tachi_msg_StrokeSample>> blade_writer;
  if (o.mouse) blade_writer.emplace(dds, bus::topics::stroke);
  bus::WaitSet waitset{dds};
  waitset.attach(topologies);
  waitset.attach(topology_deltas);
  waitset.attach(states);
  waitset.attach(strokes);
  waitset.attach(cuts);
  bus::Heartbeat heartbeat{dds, "tachi-viewer"};
  // Issue 13's boundary checks (sizes, consistent arrays) before a message is copied; SceneState then
  // checks versions, sessions and coordinates (docs/viewer.md). Both count in the heartbeat.
  bus::InputGuard guard{[&](std::string_view reason) {
    heartbeat.count_rejected(reason);
    spdlog::warn("tachi-viewer: cloth message rejected ({})", reason);
  }};

  const MouseSource mouse_source{o.mouse_sensor_id, random_session_id()};
  if (o.mouse)
    spdlog::info("tachi-viewer: mouse blade publishes as sensor {} (session {:016x}); hold the left button to cut",
                 mouse_source.sensor_id, mouse_source.session_id);
  std::optional<Window> window;
  View view;
  view.width = view.height = o.size;
  if (!o.headless) {
    window.emplace(kWindowName, cv::Size(o.size, o.size));
    if (o.mouse) window->hide_pointer();
    const cv::Size size = window->image_size();
    view.width = size.width;
    view.height = size.height;
  }
  const View home = view;
  Outputs outputs{o, cv::Size(view.width, view.height)};
  if (o.headless && !outputs.any())
    spdlog::warn("tachi-viewer: --headless without --video, --snapshot or --frames-dir: nothing will be written");

  SceneState state;
  FrameStats stats;
  std::int64_t counted_acquired_ns = 0;  // acquired_ns whose first showing the stats counted
  MouseControl mouse{o.mouse, mouse_source};
  std::string sim_blade = "-";
  std::uint64_t messages_in = 0, messages_out = 0;
  const auto frame_period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.fps));
  const auto start = Clock::now();
  auto next_frame = start;
  auto last_state = start;
  auto last_blade_sample = start;
  auto last_warning = start - kNoStateWarningPeriod;  // the first warning comes as soon as the HUD's
  cv::Mat image;
  const auto seconds = [&](Clock::time_point t) { return std::chrono::duration<double>(t - start).count(); };
  const auto count = [&](std::optional<Rejection> rejected) {
    if (rejected) heartbeat.count_rejected(to_string(*rejected));
  };

  common::run_until_stopped([&] {
    // At most 100 ms: a signal does not wake a DDS waitset, and at --fps 1 a frame is too long to stop in.
    const auto wait = std::clamp(next_frame - Clock::now(), Clock::duration(1ms), Clock::duration(100ms));
    if (window) {
      waitset.wait(std::min(wait, Clock::duration(4ms)));
      const int key = window->poll(1);
      if (!window->open()) return false;
      switch (on_key(key, view, home)) {
        case KeyAction::Quit: return false;
        case KeyAction::Snapshot: outputs.snapshot_now(); break;
        case KeyAction::ToggleHelp: state.scene().show_help = !state.scene().show_help; break;
        case KeyAction::ViewChanged:
        case KeyAction::None: break;
      }
      for (const auto& event : window->take_mouse_events())
        if (const auto sample = mouse.on_event(event, state.scene().mesh, view)) {
          blade_writer->write(*sample);
          last_blade_sample = Clock::now();
          ++messages_out;
        }
      if (Clock::now() - last_blade_sample > kBladeHoldPeriod)
        if (const auto sample = mouse.hold(state.scene().mesh, view)) {
          blade_writer->write(*sample);
          last_blade_sample = Clock::now();
          ++messages_out;
        }
    } else {
      waitset.wait(wait);
    }
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
      if (!rejected) last_state = Clock::now();
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

    const auto now = Clock::now();
    const auto without_state = now - last_state;
    std::string warning;
    if (without_state > kNoStateHudAfter) {
      warning = "no cloth state for " + std::to_string(static_cast<int>(std::chrono::duration<double>(without_state).count())) +
                " s: is tachi-sim running on domain " + std::to_string(o.bus.domain) + "?";
      if (now - last_warning > kNoStateWarningPeriod) {
        spdlog::warn("tachi-viewer: {}", warning);
        last_warning = now;
      }
    }
    // Degraded says why (the warning); running says what it waits for, if anything.
    heartbeat.update(warning.empty() ? tachi_msg_NODE_RUNNING : tachi_msg_NODE_DEGRADED, messages_in,
                     messages_out + stats.frames(),
                     !warning.empty() ? warning : state.has_cloth() ? "" : "waiting for the cloth");

    if (now >= next_frame) {
      next_frame += frame_period;
      if (now - next_frame > 5 * frame_period) next_frame = now + frame_period;  // fell behind: do not race
      if (window) {
        const cv::Size size = window->image_size();
        view.width = size.width;
        view.height = size.height;
      }
      std::optional<double> age_ms;
      if (state.shown_acquired_ns() > 0) age_ms = static_cast<double>(wall_ns() - state.shown_acquired_ns()) * 1e-6;
      // The stage's latency is capture -> the first frame that shows a new hand sample; once the hand
      // stops, the shown state's age keeps growing (the HUD shows it) but is no delay of this viewer.
      const bool new_sample_shown = state.shown_acquired_ns() > 0 && state.shown_acquired_ns() != counted_acquired_ns;
      stats.frame(now, new_sample_shown ? age_ms : std::nullopt);
      if (new_sample_shown) counted_acquired_ns = state.shown_acquired_ns();
      state.advance(seconds(now));
      Scene& scene = state.scene();
      if (!scene.hud) scene.hud.emplace();
      fill_hud(*scene.hud, state, stats, stats.latest_age_ms(), mouse.label().empty() ? sim_blade : sim_blade + " " + mouse.label(),
               heartbeat.rejected(), warning);
      scene.blade = mouse.cursor();
      image = render(scene, view);
      outputs.frame(image, now);
      if (window) window->show(image);
      heartbeat.set_metric("fps", stats.fps());
      heartbeat.set_metric("frames", static_cast<double>(stats.frames()));
      if (const auto p50 = stats.age_ms(0.5)) heartbeat.set_metric("state_age_p50_ms", *p50);
      if (const auto p99 = stats.age_ms(0.99)) heartbeat.set_metric("state_age_p99_ms", *p99);
      heartbeat.set_metric("mouse_samples", static_cast<double>(mouse.samples()));
    }
    if (o.duration_s > 0 && now - start > std::chrono::duration<double>(o.duration_s)) return false;
    if (o.exit_when_idle_s > 0 && state.states_received() > 0 && without_state > std::chrono::duration<double>(o.exit_when_idle_s))
      return false;
    return true;
  });

  if (const auto last = mouse.finish(state.scene().mesh, view)) {
    blade_writer->write(*last);
    blade_writer->wait_for_acks(300ms);  // the simulator closes the stroke; stopping stays within 1 s
  }
  if (image.empty()) image = render(state.scene(), view);
  outputs.finish(image);
  spdlog::info("tachi-viewer: {} frames rendered, {} cloth states received, {} inputs rejected", stats.frames(),
               state.states_received(), heartbeat.rejected());
  return common::kExitOk;
}

int run_mesh(const ViewerOptions& o) {
  std::string error;
  const auto mesh = read_obj(o.mesh, error);
  if (!mesh) throw std::runtime_error("--mesh: " + error);
  Scene scene;
  scene.mesh = *mesh;
  std::set<std::uint16_t> groups(mesh->groups.begin(), mesh->groups.end());
  scene.status = o.mesh + ": " + std::to_string(mesh->triangles.size()) + " triangles, " + std::to_string(groups.size()) +
                 (groups.size() == 1 ? " piece" : " pieces");
  View view;
  view.width = view.height = o.size;
  if (o.headless) {
    view = framing(scene.mesh, view);
    if (o.snapshot.empty()) spdlog::warn("tachi-viewer: --mesh --headless without --snapshot: nothing will be written");
    else write_image(o.snapshot, render(scene, view));
    return common::kExitOk;
  }
  if (std::getenv("DISPLAY") == nullptr) throw std::runtime_error("no display (DISPLAY is not set); use --headless --snapshot");
  Window window{kWindowName, cv::Size(o.size, o.size)};
  const cv::Size size = window.image_size();
  view.width = size.width;
  view.height = size.height;
  view = framing(scene.mesh, view);
  const View home = view;
  ViewerOptions no_outputs;
  no_outputs.snapshot_dir = o.snapshot_dir;
  Outputs outputs{no_outputs, size};
  MouseControl mouse{false, {}};
  cv::Mat image;
  const auto start = Clock::now();
  common::run_until_stopped([&] {
    const cv::Size now_size = window.image_size();
    view.width = now_size.width;
    view.height = now_size.height;
    image = render(scene, view);
    outputs.frame(image, Clock::now());
    window.show(image);
    const int key = window.poll(static_cast<int>(1000.0 / o.fps));
    if (!window.open()) return false;
    switch (on_key(key, view, home)) {
      case KeyAction::Quit: return false;
      case KeyAction::Snapshot: outputs.snapshot_now(); break;
      case KeyAction::ToggleHelp: scene.show_help = !scene.show_help; break;
      default: break;
    }
    for (const auto& event : window.take_mouse_events()) mouse.on_event(event, scene.mesh, view);
    return !(o.duration_s > 0 && Clock::now() - start > std::chrono::duration<double>(o.duration_s));
  });
  if (!o.snapshot.empty() && !image.empty()) write_image(o.snapshot, image);
  return common::kExitOk;
}

}  // namespace tachi::viewer
