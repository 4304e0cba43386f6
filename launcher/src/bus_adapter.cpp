#include "bus_adapter.hpp"

#include "tachi/common/process.hpp"
#include "tachi/bus/serialized.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/common/latency.hpp"

#include <cerrno>

#include <iostream>
#include <map>

namespace tachi::launcher {
namespace {
using nlohmann::json;

const char* state_name(tachi_msg_NodeState s) {
  switch (s) {
    case tachi_msg_NODE_STARTING: return "starting";
    case tachi_msg_NODE_RUNNING: return "running";
    case tachi_msg_NODE_DEGRADED: return "degraded";
    case tachi_msg_NODE_STOPPING: return "stopping";
  }
  return "?";
}

json vec(const tachi_msg_Vec3& v) { return json::array({v.x, v.y, v.z}); }

// Long arrays (positions, triangles) would drown a terminal: their length and first elements.
template <class Seq, class Each>
json sequence(const Seq& seq, bool full, Each each) {
  constexpr std::uint32_t kShown = 8;
  json items = json::array();
  const std::uint32_t n = full ? seq._length : std::min(seq._length, kShown);
  for (std::uint32_t i = 0; i < n; ++i) items.push_back(each(seq._buffer[i]));
  if (full || seq._length <= kShown) return items;
  return json{{"length", seq._length}, {"first", items}};
}
const auto same = [](auto v) { return json(v); };
const auto grid = [](const tachi_msg_GridCoord& g) { return json::array({g.u, g.v}); };

}  // namespace

template <>
json to_json(const tachi_msg_RawHandSample& m, bool) {
  return {{"sensor_id", m.sensor_id}, {"frame", m.frame},     {"capture_time_ns", m.capture_time_ns},
          {"acquired_ns", m.acquired_ns}, {"position_m", vec(m.position_m)}, {"pixel", {m.pixel_u, m.pixel_v}},
          {"confidence", m.confidence}, {"tracked", m.tracked}};
}
template <>
json to_json(const tachi_msg_VoiceCommand& m, bool) {
  return {{"source_id", m.source_id}, {"time_ns", m.time_ns}, {"command", static_cast<int>(m.command)}, {"phrase", m.phrase}};
}
template <>
json to_json(const tachi_msg_StrokeSample& m, bool) {
  return {{"sensor_id", m.sensor_id}, {"stroke_id", m.stroke_id}, {"frame", m.frame}, {"time_ns", m.time_ns},
          {"position_m", vec(m.position_m)}, {"tracked", m.tracked}, {"gate", static_cast<int>(m.gate)},
          {"opened_by", static_cast<int>(m.opened_by)}, {"closed_by", static_cast<int>(m.closed_by)},
          {"hand_outside_cloth", m.hand_outside_cloth}, {"distance_to_cloth_m", m.distance_to_cloth_m},
          {"acquired_ns", m.acquired_ns}, {"session_id", m.session_id}};
}
template <>
json to_json(const tachi_msg_ClothTopology& m, bool full) {
  return {{"cloth_id", m.cloth_id}, {"version", m.version}, {"columns", m.columns}, {"rows", m.rows},
          {"triangles", sequence(m.triangles, full, same)}, {"particle_grid", sequence(m.particle_grid, full, grid)},
          {"pinned", sequence(m.pinned, full, same)}, {"base_version", m.base_version},
          {"duplicated_from", sequence(m.duplicated_from, full, same)},
          {"changed_triangles", sequence(m.changed_triangles, full, same)}, {"session_id", m.session_id}};
}
template <>
json to_json(const tachi_msg_ClothTopologyDelta& m, bool full) {
  return {{"cloth_id", m.cloth_id}, {"session_id", m.session_id}, {"base_version", m.base_version}, {"version", m.version},
          {"new_particle_grid", sequence(m.new_particle_grid, full, grid)},
          {"new_particle_pinned", sequence(m.new_particle_pinned, full, same)},
          {"removed_triangles", sequence(m.removed_triangles, full, same)},
          {"added_triangles", sequence(m.added_triangles, full, same)},
          {"duplicated_from", sequence(m.duplicated_from, full, same)}};
}
template <>
json to_json(const tachi_msg_ClothState& m, bool full) {
  return {{"cloth_id", m.cloth_id}, {"frame", m.frame}, {"sim_time_ns", m.sim_time_ns},
          {"topology_version", m.topology_version}, {"positions", sequence(m.positions, full, same)},
          {"session_id", m.session_id}, {"acquired_ns", m.acquired_ns}, {"published_ns", m.published_ns},
          {"held_particle", m.held_particle}};
}
template <>
json to_json(const tachi_msg_CutEvent& m, bool full) {
  return {{"cloth_id", m.cloth_id}, {"stroke_id", m.stroke_id}, {"topology_version", m.topology_version},
          {"cut_line", sequence(m.cut_line, full, grid)}, {"particles_duplicated", m.particles_duplicated},
          {"pieces", m.pieces}, {"fallen_pieces", m.fallen_pieces}, {"cut_length_m", m.cut_length_m},
          {"session_id", m.session_id}, {"sensor_id", m.sensor_id}};
}
template <>
json to_json(const tachi_msg_SceneObject& m, bool full) {
  return {{"cloth_id", m.cloth_id}, {"points", sequence(m.points, full, same)}, {"session_id", m.session_id}};
}
template <>
json to_json(const tachi_msg_NodeStatus& m, bool) {
  json metrics = json::object();
  for (std::uint32_t i = 0; i < m.metrics._length; ++i) metrics[m.metrics._buffer[i].name] = m.metrics._buffer[i].value;
  return {{"node", m.node}, {"host", m.host}, {"pid", m.pid}, {"state", state_name(m.state)}, {"time_ns", m.time_ns},
          {"messages_in", m.messages_in}, {"messages_out", m.messages_out}, {"rejected", m.rejected},
          {"detail", m.detail}, {"metrics", metrics}};
}

namespace {
template <class T>
std::uint64_t echo_topic(const bus::Participant& participant, const bus::TopicSpec<T>& topic, const EchoOptions& o) {
  bus::Reader<T> reader{participant, topic, bus::ReaderKind::Observer};
  std::uint64_t printed = 0;
  const auto deadline = std::chrono::steady_clock::now() + o.timeout;
  common::run_until_stopped([&] {
    reader.wait_for_data(std::chrono::milliseconds(100));
    for (const auto& sample : reader.take()) {
      // A field is printed whole: asking for positions means all of them.
      const json j = to_json(*sample, o.full || !o.field.empty());
      if (o.field.empty()) {
        std::cout << j.dump() << '\n';
      } else if (const json* value = field_at(j, o.field)) {
        std::cout << value->dump() << '\n';
      } else {
        std::string fields;
        for (const auto& [key, v] : j.items()) fields += (fields.empty() ? "" : ", ") + key;
        throw std::invalid_argument("--field " + o.field + ": no such field in " + topic.name + " (its fields: " + fields + ")");
      }
      if (++printed == o.count) break;
    }
    std::cout.flush();
    if (o.count > 0 && printed >= o.count) return false;
    return o.timeout.count() == 0 || std::chrono::steady_clock::now() < deadline;
  });
  return printed;
}

}  // namespace

NodeReport from_msg(const tachi_msg_NodeStatus& msg) {
  NodeReport r;
  r.node = msg.node;
  r.host = msg.host;
  r.pid = msg.pid;
  r.state = state_name(msg.state);
  r.time_ns = msg.time_ns;
  r.messages_in = msg.messages_in;
  r.messages_out = msg.messages_out;
  r.rejected = msg.rejected;
  r.detail = msg.detail;
  for (std::uint32_t i = 0; i < msg.metrics._length; ++i) r.metrics[msg.metrics._buffer[i].name] = msg.metrics._buffer[i].value;
  return r;
}

RunMonitor::RunMonitor(const bus::Participant& participant, const std::filesystem::path& trace_dir)
    : status_(participant, bus::topics::node_status, bus::ReaderKind::Observer),
      hands_(participant, bus::topics::raw_hand, bus::ReaderKind::Observer),
      strokes_(participant, bus::topics::stroke, bus::ReaderKind::Observer),
      cuts_(participant, bus::topics::cut_event, bus::ReaderKind::Observer),
      waitset_(participant) {
  waitset_.attach(status_);
  waitset_.attach(hands_);
  waitset_.attach(strokes_);
  waitset_.attach(cuts_);
  trace_dir_ = trace_dir;
  std::filesystem::create_directories(trace_dir);
  const auto open = [&](std::ofstream& f, const char* name, const char* header) {
    f.open(trace_dir / name);
    if (!f) throw std::runtime_error("cannot write " + (trace_dir / name).string());
    f << header << '\n';
  };
  // received_ns: the launcher's clock when the sample arrived here (one host: the same clock as the stamps).
  open(hands_csv_, "hands.csv", "frame,acquired_ns,received_ns,tracked,x,y,z");
  open(strokes_csv_, "strokes.csv", "frame,acquired_ns,received_ns,tracked,x,y,z,gate,stroke_id");
}

void RunMonitor::poll(StatusBoard& board, std::chrono::milliseconds timeout) {
  waitset_.wait(timeout);
  const std::int64_t now = common::wall_clock_ns();
  for (const auto& s : status_.take()) board.update(from_msg(*s));
  for (const auto& h : hands_.take())
    hands_csv_ << h->frame << ',' << h->acquired_ns << ',' << now << ',' << int{h->tracked} << ',' << h->position_m.x << ','
               << h->position_m.y << ',' << h->position_m.z << '\n';
  for (const auto& s : strokes_.take())
    strokes_csv_ << s->frame << ',' << s->acquired_ns << ',' << now << ',' << int{s->tracked} << ',' << s->position_m.x << ','
                 << s->position_m.y << ',' << s->position_m.z << ',' << static_cast<int>(s->gate) << ',' << s->stroke_id << '\n';
  cut_events_ += cuts_.take().size();
  if (disk_full_) return;  // the trace stops where the disk filled; the run is ending
  for (const auto& [csv, name] : {std::pair{&hands_csv_, "hands.csv"}, std::pair{&strokes_csv_, "strokes.csv"}}) {
    csv->flush();
    if (*csv) continue;
    const int saved = errno;
    const auto file = trace_dir_ / name;
    if (!common::out_of_space(file, saved)) throw std::runtime_error("cannot write " + file.string());
    disk_full_ = file;
    return;
  }
}

bool known_topic(const std::string& topic) { return bus::find_topic(topic) != nullptr; }

const json* field_at(const json& sample, const std::string& path) {
  const json* at = &sample;
  std::size_t from = 0;
  while (from <= path.size()) {
    const std::size_t dot = std::min(path.find('.', from), path.size());
    const std::string key = path.substr(from, dot - from);
    if (at->is_object() && at->contains(key)) {
      at = &(*at)[key];
    } else if (at->is_array() && !key.empty() && key.find_first_not_of("0123456789") == std::string::npos &&
               std::stoul(key) < at->size()) {
      at = &(*at)[std::stoul(key)];
    } else {
      return nullptr;
    }
    from = dot + 1;
  }
  return at;
}

std::uint64_t echo(const bus::Participant& p, const std::string& topic, const EchoOptions& options) {
  std::uint64_t printed = 0;
  if (!bus::visit_topic(topic, [&](const auto& spec) { printed = echo_topic(p, spec, options); }))
    throw std::invalid_argument("unknown topic " + topic + "; known: " + bus::topic_names());
  return printed;
}

std::optional<TopicRate> watch_rate(const bus::Participant& participant, const bus::TopicInfo& topic, bool bandwidth,
                                    std::size_t window, std::chrono::milliseconds duration) {
  using Clock = std::chrono::steady_clock;
  bus::SerializedReader reader{participant, topic, bus::ReaderRole::RateMeter};
  bus::WaitSet waitset{participant};
  waitset.attach(reader);
  TopicRateWindow rates(window);
  std::optional<TopicRate> last;
  const auto start = Clock::now();
  auto next_report = start + std::chrono::seconds(1);
  common::run_until_stopped([&] {
    waitset.wait(std::chrono::milliseconds(100));
    // Arrival time: when this tool took the sample (as ros2 topic hz measures it).
    const auto now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
    reader.take([&](std::span<const std::byte> cdr, std::int64_t) { rates.add(now_ns, cdr.size()); });
    const auto now = Clock::now();
    if (now >= next_report) {
      next_report += std::chrono::seconds(1);
      last = rates.rate();
      std::cout << (last ? (bandwidth ? bw_report(*last) : hz_report(*last)) : "no new messages") << std::endl;
    }
    return duration.count() == 0 || now - start < duration;
  });
  return last;
}

}  // namespace tachi::launcher
