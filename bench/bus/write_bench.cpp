// What a write costs (docs/benchmarks.md, "Bus (idl/)"): dds_write of a stroke sample and of cloth
// states (64 x 64: 48 KB of positions; 128 x 128: 196 KB) through Cyclone's own type (dds_create_topic's,
// the baseline) and through the type every bus::Writer uses, whose samples are allocated at their size
// instead of taken from Cyclone's pool (idl/src/writer_sertype.cpp). Both in this process, alternating
// round by round, no reader matched: the write's serialization, allocation and history, not the network.
// Prints the median time per write of each type and the ratio.
// Then what a bus::Reader's take costs on a quiet topic (node statuses, ~3.5 KB a sample): the reader's
// own chunk of receive buffers against the baseline of 16 buffers built, zeroed and freed in every call
// (bus::Reader until the chunk moved into it), so a loop that looks every turn knows what it pays.
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <functional>
#include <vector>

namespace bus = tachi::bus;

namespace {

struct Options {
  unsigned domain = 230;
  unsigned rounds = 9;
  unsigned writes = 2000;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Nanoseconds per call of `call`, `n` calls.
double time_per_call(unsigned n, const std::function<void(unsigned)>& call) {
  const auto start = std::chrono::steady_clock::now();
  for (unsigned i = 0; i < n; ++i) call(i);
  const std::chrono::duration<double, std::nano> spent = std::chrono::steady_clock::now() - start;
  return spent.count() / n;
}

// A writer on Cyclone's own type: the topic dds_create_topic makes, as bus::Writer did before.
template <class T>
struct CycloneTypeWriter {
  dds_entity_t topic;
  dds_entity_t writer;
  CycloneTypeWriter(const bus::Participant& dds, const bus::TopicSpec<T>& spec)
      : topic(bus::detail::create_topic(dds, &bus::Descriptor<T>::value(), spec.name)),
        writer(bus::detail::create_writer(dds, topic, spec.profile, spec.name)) {}
  ~CycloneTypeWriter() { bus::detail::delete_entity(writer); }
  CycloneTypeWriter(const CycloneTypeWriter&) = delete;
  CycloneTypeWriter& operator=(const CycloneTypeWriter&) = delete;
  void write(const T& sample) { bus::check(dds_write(writer, &sample), "dds_write"); }
};

template <class T>
void compare(const char* what, const bus::Participant& dds, const bus::TopicSpec<T>& spec, T& sample,
             const std::function<void(T&, unsigned)>& vary, const Options& o) {
  CycloneTypeWriter<T> cyclone{dds, spec};
  bus::Writer<T> own{dds, spec};
  std::vector<double> cyclone_ns, own_ns;
  for (unsigned round = 0; round <= o.rounds; ++round) {  // round 0 warms both up and is not counted
    const double c = time_per_call(o.writes, [&](unsigned i) { vary(sample, i); cyclone.write(sample); });
    const double w = time_per_call(o.writes, [&](unsigned i) { vary(sample, i); own.write(sample); });
    if (round == 0) continue;
    cyclone_ns.push_back(c);
    own_ns.push_back(w);
  }
  const double c = median(cyclone_ns), w = median(own_ns);
  std::printf("%-28s Cyclone's type %9.2f us   own-size buffers %9.2f us   ratio %.2fx\n", what, c / 1000.0,
              w / 1000.0, w / c);
}

// The baseline take: 16 receive buffers made for every call, as bus::Reader::take did before.
template <class T>
std::size_t take_with_fresh_buffers(dds_entity_t reader) {
  constexpr std::size_t kChunk = 16;
  std::array<bus::Owned<T>, kChunk> samples;
  std::array<void*, kChunk> buffers;
  std::array<dds_sample_info_t, kChunk> infos;
  for (std::size_t i = 0; i < kChunk; ++i) buffers[i] = &*samples[i];
  return static_cast<std::size_t>(bus::check(dds_take(reader, buffers.data(), infos.data(), kChunk, kChunk), "dds_take"));
}

void compare_quiet_takes(const bus::Participant& dds, const Options& o) {
  bus::Reader<tachi_msg_NodeStatus> reader{dds, bus::topics::node_status};
  std::vector<double> fresh_ns, own_ns;
  std::size_t taken = 0;
  for (unsigned round = 0; round <= o.rounds; ++round) {
    const double f = time_per_call(o.writes, [&](unsigned) { taken += take_with_fresh_buffers<tachi_msg_NodeStatus>(reader.handle()); });
    const double w = time_per_call(o.writes, [&](unsigned) { taken += reader.take().size(); });
    if (round == 0) continue;
    fresh_ns.push_back(f);
    own_ns.push_back(w);
  }
  const double f = median(fresh_ns), w = median(own_ns);
  std::printf("%-28s fresh buffers  %9.2f us   reader's chunk   %9.2f us   ratio %.2fx%s\n", "take, quiet node status",
              f / 1000.0, w / 1000.0, w / f, taken ? "  (samples arrived: not quiet)" : "");
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-write-bench: the time of a dds_write through Cyclone's type and through bus::Writer's, and of a take on a quiet topic"};
  app.name("tachi-write-bench");
  Options o;
  app.add_option("--domain", o.domain, "DDS domain id (default 230)")->check(CLI::Range(0u, 232u));
  app.add_option("--rounds", o.rounds, "Rounds per type, medians over them (default 9)")->check(CLI::Range(1u, 1000u));
  app.add_option("--writes", o.writes, "Writes per round (default 2000)")->check(CLI::Range(1u, 1'000'000u));
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  bus::Participant dds{o.domain};
  std::printf("median time per write over %u rounds of %u writes, no reader matched\n", o.rounds, o.writes);

  tachi_msg_StrokeSample stroke{};
  stroke.sensor_id = 1;
  compare<tachi_msg_StrokeSample>("stroke (76 B)", dds, bus::topics::stroke, stroke,
                                  [](tachi_msg_StrokeSample& s, unsigned i) { s.frame = i; }, o);
  for (const unsigned side : {64u, 128u}) {
    std::vector<float> positions(static_cast<std::size_t>(side) * side * 3, 0.25F);
    tachi_msg_ClothState state{};
    state.cloth_id = 1;
    state.positions._buffer = positions.data();
    state.positions._length = state.positions._maximum = static_cast<std::uint32_t>(positions.size());
    state.positions._release = false;
    const std::string what = "cloth state " + std::to_string(side) + "x" + std::to_string(side) + " (" +
                             std::to_string(positions.size() * sizeof(float) / 1024) + " KiB)";
    compare<tachi_msg_ClothState>(what.c_str(), dds, bus::topics::cloth_state, state,
                                  [](tachi_msg_ClothState& s, unsigned i) { s.frame = i; }, o);
  }
  compare_quiet_takes(dds, o);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "tachi-write-bench: %s\n", e.what());
  return 1;
}
