// A peer process for the multi-process bus tests: publishes or subscribes one kind of traffic
// on the real topics and prints what happened as one JSON line, so the test can check it.
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <map>
#include <thread>
#include <vector>

using namespace std::chrono_literals;
namespace bus = tachi::bus;

namespace {

struct Options {
  std::string role;
  tachi::common::BusOptions bus;
  unsigned keys = 4;
  unsigned count = 120;
  double rate_hz = 60.0;
  unsigned bytes = 200'000;
  double timeout_s = 20.0;
  double linger_s = 5.0;
};

float pattern(std::uint64_t frame, std::size_t i) { return static_cast<float>((frame * 7919 + i) % 100003); }

void pace(std::chrono::steady_clock::time_point start, unsigned i, double rate_hz) {
  std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                            std::chrono::duration<double>(i / rate_hz)));
}

int publish_strokes(const Options& o, bus::Participant& dds) {
  bus::Writer<tachi_msg_StrokeSample> writer{dds, bus::topics::stroke};
  if (!writer.wait_for_readers(1, std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(o.timeout_s))))
    throw std::runtime_error("no reader matched within " + std::to_string(o.timeout_s) + " s");
  const auto start = std::chrono::steady_clock::now();
  for (unsigned i = 0; i < o.count; ++i) {
    pace(start, i, o.rate_hz);
    for (unsigned key = 1; key <= o.keys; ++key) {
      tachi_msg_StrokeSample s{};
      s.sensor_id = key;
      s.frame = i;
      s.stroke_id = key * 1000 + i;
      s.position_m = {0.001f * static_cast<float>(i), -0.5f, static_cast<float>(key)};
      writer.write(s);
    }
  }
  const bool acked = writer.wait_for_acks(10s);
  std::cout << nlohmann::json{{"sent", o.count * o.keys}, {"acked", acked}}.dump() << std::endl;
  return acked ? 0 : 1;
}

int subscribe_strokes(const Options& o, bus::Participant& dds) {
  bus::Reader<tachi_msg_StrokeSample> reader{dds, bus::topics::stroke};
  std::map<std::uint32_t, std::uint64_t> next_frame;
  unsigned received = 0, out_of_order = 0, corrupt = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  // Until the count, the timeout, or SIGINT/SIGTERM (a test that listens for the length of a run stops it).
  while (received < o.keys * o.count && std::chrono::steady_clock::now() < deadline && !tachi::common::stop_requested()) {
    reader.wait_for_data(100ms);
    for (const auto& s : reader.take()) {
      auto& expected = next_frame[s->sensor_id];
      if (s->frame != expected) ++out_of_order;
      expected = s->frame + 1;
      if (s->stroke_id != s->sensor_id * 1000 + s->frame || s->position_m.z != static_cast<float>(s->sensor_id)) ++corrupt;
      ++received;
    }
  }
  const bool ok = received == o.keys * o.count && out_of_order == 0 && corrupt == 0 && next_frame.size() == o.keys;
  std::cout << nlohmann::json{{"received", received}, {"keys", next_frame.size()}, {"out_of_order", out_of_order},
                              {"corrupt", corrupt}}
                   .dump()
            << std::endl;
  return ok ? 0 : 1;
}

int publish_states(const Options& o, bus::Participant& dds) {
  bus::Writer<tachi_msg_ClothState> writer{dds, bus::topics::cloth_state};
  if (!writer.wait_for_readers(1, 20s)) throw std::runtime_error("no reader matched within 20 s");
  std::vector<float> positions(o.bytes / sizeof(float));
  const auto start = std::chrono::steady_clock::now();
  for (unsigned i = 0; i < o.count; ++i) {
    pace(start, i, o.rate_hz);
    for (std::size_t k = 0; k < positions.size(); ++k) positions[k] = pattern(i, k);
    tachi_msg_ClothState s{};
    s.cloth_id = 1;
    s.frame = i;
    s.topology_version = 1;
    // Zero-copy write: the sequence points at our buffer and Cyclone must not free it.
    s.positions._buffer = positions.data();
    s.positions._length = s.positions._maximum = static_cast<std::uint32_t>(positions.size());
    s.positions._release = false;
    writer.write(s);
  }
  const bool acked = writer.wait_for_acks(10s);
  std::cout << nlohmann::json{{"sent", o.count}, {"acked", acked}}.dump() << std::endl;
  return acked ? 0 : 1;
}

// The State profile keeps the last 2 states: a reader that falls more than two behind (a loaded
// machine) skips stale ones by design. What must hold: every state taken is intact, none comes back
// in time, the newest (the last sent) always arrives, and skips stay rare (at most 5 %).
int subscribe_states(const Options& o, bus::Participant& dds) {
  bus::Reader<tachi_msg_ClothState> reader{dds, bus::topics::cloth_state};
  unsigned received = 0, backwards = 0, skipped = 0, corrupt = 0;
  std::uint64_t expected = 0;
  bool got_last = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  while (!got_last && std::chrono::steady_clock::now() < deadline) {
    reader.wait_for_data(100ms);
    for (const auto& s : reader.take()) {
      if (s->frame < expected) ++backwards;
      if (s->frame > expected) skipped += static_cast<unsigned>(s->frame - expected);
      expected = s->frame + 1;
      got_last = got_last || s->frame + 1 == o.count;
      bool good = s->positions._length == o.bytes / sizeof(float);
      for (std::size_t k = 0; good && k < s->positions._length; k += 97) good = s->positions._buffer[k] == pattern(s->frame, k);
      if (!good) ++corrupt;
      ++received;
    }
  }
  std::cout << nlohmann::json{{"received", received}, {"skipped", skipped}, {"backwards", backwards}, {"corrupt", corrupt},
                              {"newest_arrived", got_last}}
                   .dump()
            << std::endl;
  return got_last && backwards == 0 && corrupt == 0 && skipped * 20 <= o.count ? 0 : 1;
}

int publish_topology(const Options& o, bus::Participant& dds) {
  bus::Writer<tachi_msg_ClothTopology> writer{dds, bus::topics::cloth_topology};
  std::vector<std::uint32_t> triangles{0, 1, 2, 1, 3, 2};
  for (std::uint32_t version = 1; version <= 3; ++version) {
    tachi_msg_ClothTopology t{};
    t.cloth_id = 7;
    t.version = version;
    t.columns = t.rows = 2;
    t.triangles._buffer = triangles.data();
    t.triangles._length = t.triangles._maximum = static_cast<std::uint32_t>(triangles.size());
    t.triangles._release = false;
    writer.write(t);
  }
  std::cout << nlohmann::json{{"published", 3}}.dump() << std::endl;
  // Transient-local data lives in the writer: stay until the late reader has been served.
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.linger_s);
  while (!tachi::common::stop_requested() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(20ms);
  return 0;
}

int subscribe_topology(const Options& o, bus::Participant& dds) {
  bus::Reader<tachi_msg_ClothTopology> reader{dds, bus::topics::cloth_topology};
  std::vector<std::uint32_t> versions;
  std::size_t triangles = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  while (versions.empty() && std::chrono::steady_clock::now() < deadline) {
    reader.wait_for_data(100ms);
    for (const auto& t : reader.take()) {
      versions.push_back(t->version);
      triangles = t->triangles._length / 3;
    }
  }
  // A later sample (if any) would arrive right behind the first: give it a moment.
  reader.wait_for_data(200ms);
  for (const auto& t : reader.take()) versions.push_back(t->version);
  std::cout << nlohmann::json{{"versions", versions}, {"triangles", triangles}}.dump() << std::endl;
  return versions == std::vector<std::uint32_t>{3} && triangles == 2 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"bus_peer: one side of a multi-process bus test"};
  app.name("bus_peer");
  Options o;
  app.add_option("role", o.role, "What to do")
      ->required()
      ->check(CLI::IsMember({"strokes-pub", "strokes-sub", "states-pub", "states-sub", "topology-pub", "topology-sub"}));
  tachi::common::add_bus_flags(app, o.bus);
  app.add_option("--keys", o.keys, "Instances (sensor ids)")->check(CLI::Range(1u, 64u));
  app.add_option("--count", o.count, "Samples per key")->check(CLI::Range(1u, 100000u));
  app.add_option("--rate", o.rate_hz, "Publication rate, Hz")->check(CLI::Range(1.0, 10000.0));
  app.add_option("--bytes", o.bytes, "Cloth state payload size")->check(CLI::Range(4u, 16'000'000u));
  app.add_option("--timeout", o.timeout_s, "Subscriber gives up (stroke publisher waits for a reader) after this many seconds")->check(CLI::PositiveNumber);
  app.add_option("--linger", o.linger_s, "Topology publisher stays this long")->check(CLI::NonNegativeNumber);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::install_stop_handlers();

  bus::Participant dds{o.bus.domain, o.bus.dds_config, {o.bus.secure_dir, o.bus.identity}};
  if (o.role == "strokes-pub") return publish_strokes(o, dds);
  if (o.role == "strokes-sub") return subscribe_strokes(o, dds);
  if (o.role == "states-pub") return publish_states(o, dds);
  if (o.role == "states-sub") return subscribe_states(o, dds);
  if (o.role == "topology-pub") return publish_topology(o, dds);
  return subscribe_topology(o, dds);
} catch (const std::exception& e) {
  std::cerr << "bus_peer: " << e.what() << '\n';
  return 1;
}
