// tachi-filter: raw hand samples -> smoothed, gated strokes. Offline (CSV in, CSV out) or on the DDS bus.
#include "bus_adapter.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/input_guard.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/latency.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/filter/config.hpp"
#include "tachi/filter/hand_csv.hpp"
#include "tachi/filter/journal.hpp"
#include "tachi/filter/stroke_filter.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

namespace {

struct Options {
  bool offline = false;
  std::string hands_csv;
  std::string out_csv;
  std::string voice_csv;
  std::string config_file;
  std::string smoother;
  std::string gate;
  bool camera_frame = false;
  bool print_config = false;
  std::string journal;
  std::string log_level;
  tachi::common::BusOptions bus;
};

// A Kinect v1 sees 0.4-4 m; a camera-frame hand beyond 20 m on any axis is a faulty or hostile peer.
constexpr float kMaxHandRange_m = 20.0F;
// A cloth particle further than this from the origin is a faulty state (the viewer's and the simulator's bound).
constexpr float kMaxClothRange_m = 100.0F;
// Hand samples carry no session id: a sensor whose clock jumps back by more than this restarted.
constexpr std::int64_t kSensorRestartGap_ns = 1'000'000'000;
// The largest cloth tachi-sim builds (4096 x 4096 particles, cut up to twice over), xyz each.
constexpr std::size_t kMaxClothFloats = std::size_t{3} * 4096 * 4096 * 2;

struct TimedCommand {
  double time_s;
  tachi::filter::VoiceCommandKind kind;
};

// tachi-voice's output (time_s,command,phrase), for replaying voice gating offline.
std::vector<TimedCommand> read_voice_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read voice commands " + path);
  std::vector<TimedCommand> commands;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line.starts_with("time_s")) continue;
    std::istringstream cells(line);
    std::string time, command;
    std::getline(cells, time, ',');
    std::getline(cells, command, ',');
    char* end = nullptr;
    const double t = std::strtod(time.c_str(), &end);
    using Kind = tachi::filter::VoiceCommandKind;
    const Kind kind = command == "start" ? Kind::Start : command == "stop" ? Kind::Stop : command == "grab" ? Kind::Grab : Kind::Release;
    if (end == time.c_str() || (command != "start" && command != "stop" && command != "grab" && command != "release")) {
      spdlog::warn("{} line {}: expected time_s,start|stop|grab|release,phrase; skipped", path, line_no);
      continue;
    }
    commands.push_back({t, kind});
  }
  std::stable_sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.time_s < b.time_s; });
  return commands;
}

int run_offline(const Options& o, const tachi::filter::FilterConfig& config) {
  std::ifstream in(o.hands_csv);
  if (!in) throw std::runtime_error("cannot read " + o.hands_csv);
  const auto hands = tachi::filter::read_hand_csv(in);
  for (const auto& why : hands.skipped) spdlog::warn("{}: {}; row skipped", o.hands_csv, why);
  const auto commands = o.voice_csv.empty() ? std::vector<TimedCommand>{} : read_voice_csv(o.voice_csv);

  std::ofstream out(o.out_csv);
  if (!out) throw std::runtime_error("cannot write " + o.out_csv);
  tachi::filter::StrokeFilter filter{config};
  tachi::filter::write_stroke_csv_header(out);
  std::size_t next_command = 0;
  const std::int64_t t0 = hands.samples.empty() ? 0 : hands.samples.front().stamp_ns;
  std::uint32_t strokes = 0;
  for (const auto& hand : hands.samples) {
    // Voice time 0 is the first hand sample: the recording's audio track starts with its video.
    const double t = static_cast<double>(hand.stamp_ns - t0) * 1e-9;
    while (next_command < commands.size() && commands[next_command].time_s <= t) {
      if (const auto why = filter.on_voice(commands[next_command++].kind)) spdlog::warn("{}", *why);
    }
    const auto stroke = filter.on_hand(hand);
    strokes = stroke.stroke_id;
    tachi::filter::write_stroke_csv_row(out, stroke, o.camera_frame);
  }
  out.flush();
  if (!out) throw std::runtime_error("write failed: " + o.out_csv);
  spdlog::info("{} samples ({} skipped, {} outliers), {} strokes -> {}", hands.samples.size(), hands.skipped.size(),
               filter.outliers(), strokes, o.out_csv);
  return tachi::common::kExitOk;
}

int run_bus(const Options& o, const tachi::filter::FilterConfig& config) {
  namespace bus = tachi::bus;
  using namespace std::chrono_literals;
  bus::Participant dds{o.bus.domain, o.bus.dds_config, {o.bus.secure_dir, o.bus.identity}};
  bus::Reader<tachi_msg_RawHandSample> hands{dds, bus::topics::raw_hand};
  bus::Reader<tachi_msg_VoiceCommand> voice{dds, bus::topics::voice_command};
  bus::Reader<tachi_msg_ClothState> cloth{dds, bus::topics::cloth_state};
  bus::Writer<tachi_msg_StrokeSample> strokes{dds, bus::topics::stroke};
  bus::WaitSet waitset{dds};
  waitset.attach(hands);
  waitset.attach(voice);
  waitset.attach(cloth);

  bus::Heartbeat heartbeat{dds, "tachi-filter"};
  // Hostile or faulty input is refused before the filter sees it, and counted in the heartbeat.
  bus::InputGuard guard{[&](std::string_view reason) {
    heartbeat.count_rejected(reason);
    if (heartbeat.rejected() == 1 || heartbeat.rejected() % 100 == 0)
      spdlog::warn("{} input samples rejected (last: {})", heartbeat.rejected(), reason);
  }};
  tachi::filter::StrokeFilter filter{config};
  // No lost cuts: a journal left by a killed run is replayed first (same state, same session), and
  // the hand samples it already holds are skipped when the sensor's history delivers them again.
  std::optional<tachi::filter::FilterJournal> journal;
  tachi::filter::ProcessedSamples processed;
  std::vector<tachi_msg_StrokeSample> resend;
  if (!o.journal.empty()) {
    journal.emplace(o.journal, config, bus::new_session_id());
    if (!journal->recovered().empty()) {
      const auto t0 = std::chrono::steady_clock::now();
      auto replayed = tachi::filter::replay(journal->recovered(), filter);
      processed = std::move(replayed.processed);
      // The last sample was journaled before it was published: if the kill fell in between, the
      // simulator never got it. Sent again (the strokes topic is transient-local): at worst a duplicate.
      if (replayed.last) resend.push_back(tachi::filter::to_msg(replayed.last->second, replayed.last->first, journal->session_id()));
      spdlog::info("tachi-filter: replayed {} journal records from {} in {:.0f} ms: session {:x} goes on at stroke {} ({})",
                   journal->recovered().size(), o.journal,
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(),
                   journal->session_id(), filter.gate().status().stroke_id,
                   tachi::filter::to_string(filter.gate().status().phase));
    }
  }
  const std::uint64_t session_id = journal ? journal->session_id() : bus::new_session_id();
  bool journal_full_said = false;
  const auto warn_journal_full = [&] {
    if (journal_full_said) return;
    journal_full_said = true;
    spdlog::warn("tachi-filter: journal {} reached {} MB; no longer journaling (a restart from here would lose the rest)",
                 o.journal, tachi::filter::FilterJournal::kMaxBytes >> 20);
  };
  // A recovered gate measures the hand against the cloth it was cutting: wait (up to 1 s) for the
  // simulator's next state rather than judging the catch-up samples against the flat rest cloth.
  const bool recovering = journal && !journal->recovered().empty();
  const auto cloth_due = std::chrono::steady_clock::now() + 1s;
  bool cloth_seen = false;
  std::uint64_t in_count = 0;
  std::uint64_t out_count = 0;
  std::uint64_t redelivered = 0;
  std::vector<tachi_msg_StrokeSample> batch = std::move(resend);
  tachi::common::LatencyWindow latency;
  tachi::common::PeerWait waiting_for_sensor("tachi-sensor", o.bus.domain);
  spdlog::info("tachi-filter on domain {}: gate {}, smoother {}", o.bus.domain, tachi::filter::to_string(config.gate.mode),
               tachi::filter::to_string(config.smoother.kind));
  tachi::common::install_stop_handlers();
  tachi::common::run_until_stopped([&] {
    waitset.wait(100ms);
    // Commands first: one spoken before a hand sample arrived applies to that sample.
    for (const auto& c : voice.take()) {
      static constexpr const char* kNames[] = {"start", "stop", "grab", "release"};
      const auto command = tachi::filter::from_msg(*c);
      spdlog::info("voice command {} (\"{}\")", kNames[static_cast<int>(command)], c->phrase);
      if (const auto why = filter.on_voice(command)) spdlog::warn("{}", *why);
      if (journal && !journal->append({tachi::filter::FilterJournalRecord::Kind::Voice, 0, {}, {}, command}))
        warn_journal_full();
    }
    const bool take_hands = !recovering || cloth_seen || std::chrono::steady_clock::now() >= cloth_due;
    for (const auto& h : take_hands ? hands.take() : std::vector<bus::Owned<tachi_msg_RawHandSample>>{}) {
      if (processed.contains(h->sensor_id, h->capture_time_ns)) {
        ++redelivered;  // processed before the restart (or a frame sent twice): not a new sample
        continue;
      }
      ++in_count;
      if (h->tracked && !guard.position(h->position_m.x, h->position_m.y, h->position_m.z, kMaxHandRange_m)) continue;
      if (!guard.time(h->sensor_id, h->capture_time_ns, bus::InputGuard::now_ns(), kSensorRestartGap_ns)) continue;
      const auto hand = tachi::filter::from_msg(*h);
      const auto stroke = filter.on_hand(hand);
      processed.add(h->sensor_id, h->capture_time_ns);
      if (journal && !journal->append({tachi::filter::FilterJournalRecord::Kind::Hand, h->sensor_id, hand,
                                       {stroke.distance_to_cloth_m, stroke.hand_outside_cloth, {}}, {}}))
        warn_journal_full();
      auto msg = tachi::filter::to_msg(stroke, h->sensor_id, session_id);
      msg.acquired_ns = h->acquired_ns;  // the depth frame's time rides on to the simulator
      batch.push_back(msg);
      heartbeat.set_metric("strokes", stroke.stroke_id);
      heartbeat.set_metric("outliers", static_cast<double>(filter.outliers()));  // impossibly fast samples
      heartbeat.set_metric("gate", static_cast<double>(msg.gate));
      heartbeat.set_metric("gate_opened_by", static_cast<double>(msg.opened_by));
    }
    // Journaled before published: a sample the simulator has, the journal has.
    if (journal) journal->flush();
    for (const auto& msg : batch) {
      strokes.write(msg);
      if (msg.acquired_ns > 0) latency.add_since(msg.acquired_ns, tachi::common::wall_clock_ns());
      ++out_count;
    }
    if (!batch.empty()) {
      heartbeat.set_metric("latency_p50_ms", latency.percentile(50));
      heartbeat.set_metric("latency_p99_ms", latency.percentile(99));
    }
    batch.clear();
    if (!take_hands) std::this_thread::sleep_for(5ms);  // the waitset stays triggered by the waiting hands
    waiting_for_sensor.warn_if_waiting(hands.matched_writers() > 0);
    // The cloth after the hands: a 128 x 128 state is 196 KB to copy and scan, and the hand samples
    // must not wait for it (end-to-end latency); the gate then uses the cloth as of one state earlier.
    auto states = cloth.take();
    if (!states.empty()) {
      const auto& newest = *states.back();
      if (guard.size(newest.positions._length, kMaxClothFloats, 3) &&
          guard.positions(newest.positions._buffer, newest.positions._length, kMaxClothRange_m)) {
        filter.on_cloth_state({newest.positions._buffer, newest.positions._length});
        cloth_seen = true;
      }
    }
    heartbeat.set_metric("redelivered", static_cast<double>(redelivered));
    heartbeat.update(tachi_msg_NODE_RUNNING, in_count, out_count, "gate " + tachi::filter::to_string(config.gate.mode));
    return true;
  });
  spdlog::info("stopping: {} hand samples in, {} stroke samples out", in_count, out_count);
  return tachi::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-filter: smooths raw hand samples, maps them onto the cloth and gates cutting strokes"};
  app.name("tachi-filter");
  Options o;
  app.add_flag("--offline", o.offline, "Read a hand CSV and write a stroke CSV instead of joining the DDS bus");
  app.add_option("--hands", o.hands_csv, "Offline input: the sensor's CSV (frame,stamp_ns,x,y,z,u,v,tracked,confidence)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", o.out_csv, "Offline output: frame,stamp_ns,x,y,z,gate,stroke_id");
  app.add_option("--voice", o.voice_csv,
                 "Offline: voice commands as tachi-voice prints them (time_s,command,phrase; time 0 = first hand sample)")
      ->check(CLI::ExistingFile);
  app.add_option("--config", o.config_file, "Filter config JSON (see config/filter.json); defaults built in")
      ->check(CLI::ExistingFile);
  app.add_option("--smoother", o.smoother, "Override the config's smoother")
      ->check(CLI::IsMember({"wiener", "one-euro", "moving-average", "none"}));
  app.add_option("--gate", o.gate, "Override the config's gate mode")->check(CLI::IsMember({"threshold", "voice", "either"}));
  app.add_flag("--camera-frame", o.camera_frame, "Offline: write camera-frame positions instead of world-frame ones");
  app.add_flag("--print-config", o.print_config, "Print the effective config as JSON and exit");
  app.add_option("--journal", o.journal,
                 "Journal every hand sample and voice command to this file; started again with the same file, the "
                 "filter replays it and carries the open stroke on under the same session (tachi run passes it)");
  tachi::common::add_log_level_flag(app, o.log_level);
  tachi::common::add_bus_flags(app, o.bus);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  // Logs go to stderr: stdout carries the command lines (tachi-voice) and must stay parseable.
  tachi::common::set_log_level(o.log_level);

  tachi::filter::FilterConfig config;
  try {
    if (!o.config_file.empty()) config = tachi::filter::load_filter_config(o.config_file);
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi-filter: --config " << o.config_file << ": " << e.what() << '\n';
    return tachi::common::kExitUsage;
  }
  if (!o.smoother.empty()) config.smoother.kind = *tachi::filter::smoother_kind_from_string(o.smoother);
  if (!o.gate.empty()) config.gate.mode = *tachi::filter::gate_mode_from_string(o.gate);
  if (o.print_config) {
    std::cout << tachi::filter::to_json(config) << '\n';
    return tachi::common::kExitOk;
  }
  if (o.offline) {
    if (!o.journal.empty()) {
      std::cerr << "tachi-filter: --journal is for the DDS filter, not --offline\n";
      return tachi::common::kExitUsage;
    }
    if (o.hands_csv.empty() || o.out_csv.empty()) {
      std::cerr << "tachi-filter: --offline needs --hands IN.csv and --out OUT.csv\n";
      return tachi::common::kExitUsage;
    }
    return run_offline(o, config);
  }
  if (!o.hands_csv.empty() || !o.out_csv.empty() || !o.voice_csv.empty() || o.camera_frame) {
    std::cerr << "tachi-filter: --hands, --out, --voice and --camera-frame need --offline\n";
    return tachi::common::kExitUsage;
  }
  return run_bus(o, config);
} catch (const std::exception& e) {
  std::cerr << "tachi-filter: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
