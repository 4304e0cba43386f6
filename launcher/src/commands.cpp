#include "commands.hpp"

#include "preflight.hpp"
#include "run.hpp"
#include "tachi/bus/discovery.hpp"
#include "tachi/bus/run_partition.hpp"
#include "tachi/launcher/config.hpp"
#include "tachi/launcher/supervision.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>

namespace tachi::launcher {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// Defaults, then the config file, then the flags that were given, then --set.
json effective_config(const RunFlags& f) {
  json config = default_config_json(std::getenv("DISPLAY") != nullptr && *std::getenv("DISPLAY") != '\0');
  if (!f.config_file.empty()) {
    std::ifstream in(f.config_file);
    json file = json::parse(in, nullptr, false);
    if (file.is_discarded() || !file.is_object()) throw std::invalid_argument("--config " + f.config_file + ": not a JSON object");
    merge_into(config, file);
  }
  const auto given = [&](const char* flag) { return f.has(flag); };
  if (given("--recording")) {
    config["recording"] = f.recording;
    config.erase("live");
  }
  if (given("--live")) {
    config["recording"] = "";
    config["live"] = true;
  }
  if (given("--rate")) config["rate"] = f.rate;
  if (given("--gate")) config["gate"] = f.gate;
  if (given("--voice-wav")) config["voice_wav"] = f.voice_wav;
  if (given("--voice-device")) config["voice_device"] = f.voice_device;
  if (given("--blade")) config["blade"] = f.blade;
  if (given("--grid")) config["grid"] = f.grid;
  if (given("--domain")) config["domain"] = f.domain;
  if (given("--dds-config")) config["dds_config"] = fs::absolute(f.dds_config).string();
  if (given("--lossy")) config["lossy"] = f.lossy;
  if (given("--secure")) config["secure"] = fs::absolute(f.secure).string();
  if (given("--out")) config["out"] = f.out;
  if (given("--headless")) config["headless"] = f.headless;
  if (given("--nodes")) config["nodes"] = f.nodes;
  if (given("--settle")) config["settle_s"] = f.settle_s;
  if (given("--mouse")) config["mouse"] = f.mouse;
  if (given("--in-process")) config["in_process"] = f.in_process;
  for (const auto& s : f.sets) merge_into(config, parse_set(s));
  return config;
}

// The launcher's own figures join the run's summary.json once the run wrote it.
void add_to_summary(const fs::path& out, const json& figures) {
  std::ifstream in(out / "summary.json");
  json summary = json::parse(in, nullptr, false);
  in.close();
  if (!summary.is_object()) return;
  for (const auto& [key, value] : figures.items()) summary[key] = value;
  std::ofstream(out / "summary.json") << summary.dump(2) << '\n';
}

// The nodes of another pipeline on this run's domain that this run would start again ("tachi-sim on
// host h, pid 123, ..."), from DDS discovery (Cyclone announces each participant's process, host and
// pid). Only the same nodes conflict: one pipeline split over two hosts (`--nodes`) shares a domain.
std::string live_pipeline_nodes(const RunConfig& config) {
  bus::Participant dds{config.domain, config.dds_config, {config.secure, "monitor"}};
  const auto snapshot = bus::discover(dds, std::chrono::milliseconds(500));
  std::string live;
  for (const auto& p : snapshot.participants) {
    if (p.self || !p.process.starts_with("tachi-") || !config.has(p.process.substr(6))) continue;
    live += (live.empty() ? "" : ", ") + p.process + " on host " + p.host + ", pid " + p.pid;
  }
  return live;
}

int cmd_run(const RunFlags& f, const fs::path& bin_dir) {
  RunConfig config;
  json effective;
  try {
    effective = effective_config(f);
    config = from_json(effective);
  } catch (const std::exception& e) {
    std::cerr << "tachi run: " << e.what() << '\n';
    return kRunUsage;
  }
  if (f.print_config) {
    std::cout << to_json(config).dump(2) << '\n';
    return kRunOk;
  }
  if (!config.recording.empty() && !fs::exists(fs::path(config.recording) / "INDEX.txt")) {
    std::cerr << "tachi run: --recording " << config.recording << ": not a fakenect recording (no INDEX.txt)\n";
    return kRunUsage;
  }
  if (!config.recording.empty()) config.recording = fs::absolute(config.recording).string();
  // Before any node starts: a mistake is named now, and no headline follows that could pass for a run.
  auto error = check_out_folder(config, estimate_output_bytes(config));
  if (!error) error = check_node_flags(config, bin_dir);
  if (error) {
    std::cerr << "tachi run: " << error->message << '\n';
    return error->exit_code;
  }
  common::install_stop_handlers();
  // The run id names the DDS partition of every node of this run (bus/run_partition.hpp), passed down in
  // the environment. A whole pipeline gets a fresh one, secure or not (the grants allow every partition,
  // scripts/make_test_pki.sh); one split over launchers (--nodes) shares the default partition unless each
  // is given the same --run-id.
  std::string run_id = f.run_id;
  if (run_id.empty() && !f.has("--nodes"))
    run_id = fmt::format("{:016x}", bus::new_session_id());
  if (!run_id.empty()) ::setenv(bus::kRunIdEnv, run_id.c_str(), 1);
  else ::unsetenv(bus::kRunIdEnv);
  if (const auto live = live_pipeline_nodes(config); !live.empty()) {
    std::cerr << "tachi run: DDS domain " << config.domain << " already has a live tachi pipeline: " << live
              << "; two pipelines on one domain would mix their samples. Stop it, or give this run another --domain\n";
    return kRunFailure;
  }
  if (!f.record) {
    std::error_code ignored;
    fs::remove(fs::path(config.out) / "run.mcap", ignored);  // a previous run's recording must not pass for this run's
    const int rc = run(config, {bin_dir, plot_script(bin_dir)});
    add_to_summary(config.out, {{"run_id", run_id}});
    return rc;
  }

  // --record: the whole bus of the run into <out>/run.mcap, from before the first node starts until
  // the last one stopped; the recorder's own figures join summary.json.
  const fs::path out(config.out);
  fs::create_directories(out);
  bus::Participant dds{config.domain, config.dds_config, {config.secure, "monitor"}};
  RecordOptions record_options;
  record_options.file = out / "run.mcap";
  record_options.foxglove = f.foxglove;
  BackgroundRecorder recorder{dds, record_options};
  const int rc = run(config, {bin_dir, plot_script(bin_dir)});
  const auto recorded = recorder.stop();
  spdlog::info("recorded {} messages ({} lost) into {}", recorded.total, recorded.lost, (out / "run.mcap").string());
  add_to_summary(out, {{"run_id", run_id},
                       {"recording", {{"file", "run.mcap"}, {"messages", recorded.messages}, {"lost", recorded.lost}, {"bytes", recorded.bytes},
                                     {"ended", recorded.ended}}}});
  return rc;
}

int cmd_record(const common::BusOptions& b, const RecordOptions& options) {
  if (const auto unknown = unknown_topics(options.topics); !unknown.empty()) {
    std::cerr << "tachi record: --topics: unknown topic " << unknown.front() << "; known: " << bus::topic_names() << '\n';
    return common::kExitUsage;
  }
  bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  Recorder recorder{dds, options};
  spdlog::info("recording domain {} into {} (Ctrl-C stops)", b.domain, options.file.string());
  while (!common::stop_requested() && recorder.poll(std::chrono::milliseconds(100))) {
  }
  const auto r = recorder.finish("stopped by signal");
  std::cout << json{{"file", options.file.string()}, {"messages", r.total}, {"topics", r.messages}, {"lost", r.lost},
                    {"bytes", r.bytes}, {"ended", r.ended}}
                   .dump()
            << '\n';
  return common::kExitOk;
}

int cmd_play(const common::BusOptions& b, const PlayOptions& options) {
  if (const auto unknown = unknown_topics(options.topics); !unknown.empty()) {
    std::cerr << "tachi play: --topics: unknown topic " << unknown.front() << "; known: " << bus::topic_names() << '\n';
    return common::kExitUsage;
  }
  bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  const auto r = play(dds, options);
  std::cout << json{{"file", options.file.string()}, {"published", r.published}, {"skipped", r.skipped}}.dump() << '\n';
  return common::kExitOk;
}

int cmd_topics(const common::BusOptions& b, double listen_s, bool verbose) {
  bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  const auto snapshot = bus::discover(dds, std::chrono::milliseconds(static_cast<int>(listen_s * 1000)));
  std::map<std::string, const bus::ParticipantInfo*> by_key;
  std::cout << "participants on domain " << b.domain << ":\n";
  for (const auto& p : snapshot.participants) {
    by_key[p.key] = &p;
    if (p.self) continue;
    std::cout << "  " << (p.process.empty() ? "?" : p.process) << "  host " << (p.host.empty() ? "?" : p.host) << "  pid "
              << (p.pid.empty() ? "?" : p.pid) << "  guid " << p.key << '\n';
  }
  struct Counts {
    std::string type;
    std::vector<std::string> writers, readers;
  };
  std::map<std::string, Counts> topics;
  for (const auto& e : snapshot.endpoints) {
    const auto p = by_key.find(e.participant_key);
    if (p != by_key.end() && p->second->self) continue;
    auto& t = topics[e.topic];
    t.type = e.type;
    const std::string who = p == by_key.end() || p->second->process.empty() ? e.participant_key
                                                                             : p->second->process + "[" + p->second->pid + "]";
    (e.writer ? t.writers : t.readers).push_back(verbose ? who + "  QoS: " + e.qos : who);
  }
  std::cout << "topics:\n";
  for (const auto& [name, t] : topics) {
    std::cout << "  " << name << "  (" << t.type << ")  " << t.writers.size() << " writer(s), " << t.readers.size()
              << " reader(s)\n";
    for (const auto& w : t.writers) std::cout << "    writer " << w << '\n';
    for (const auto& r : t.readers) std::cout << "    reader " << r << '\n';
  }
  return common::kExitOk;
}

int cmd_status(const common::BusOptions& b, double listen_s) {
  bus::Participant dds{b.domain, b.dds_config, {b.secure_dir, b.identity}};
  bus::Reader<tachi_msg_NodeStatus> reader{dds, bus::topics::node_status, bus::ReaderKind::Observer};
  StatusBoard board;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(listen_s);
  // Transient-local: each node's latest heartbeat arrives as soon as it is discovered.
  while (std::chrono::steady_clock::now() < deadline && !common::stop_requested()) {
    reader.wait_for_data(std::chrono::milliseconds(100));
    for (const auto& s : reader.take()) board.update(from_msg(*s));
  }
  if (board.nodes().empty()) {
    std::cout << "no heartbeats on domain " << b.domain << '\n';
    return common::kExitFailure;
  }
  for (const auto& [name, r] : board.nodes()) {
    std::cout << name << "  host " << r.host << "  pid " << r.pid << "  " << r.state << "  in " << r.messages_in << "  out "
              << r.messages_out << "  rejected " << r.rejected << (r.detail.empty() ? "" : "  \"" + r.detail + "\"") << '\n';
    for (const auto& [metric, value] : r.metrics) std::cout << "    " << metric << " " << value << '\n';
  }
  std::cout << board.line(0) << '\n';
  return common::kExitOk;
}

}  // namespace

fs::path self_dir(const char* argv0) {
  std::error_code ec;
  const auto exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::absolute(argv0).parent_path() : exe.parent_path();
}

int dispatch(const Command& c, const fs::path& bin_dir) {
  if (c.subcommand == Subcommand::Run) return cmd_run(c.run, bin_dir);
  common::install_stop_handlers();
  // Bus tools read every run's partition; record and play may name one run.
  if (!c.tool_run_id.empty()) ::setenv(bus::kRunIdEnv, c.tool_run_id.c_str(), 1);
  else if (c.subcommand != Subcommand::Play) bus::read_every_run();
  switch (c.subcommand) {
    case Subcommand::Run: break;
    case Subcommand::Topics: return cmd_topics(c.bus, c.listen_s, c.verbose);
    case Subcommand::Status: return cmd_status(c.bus, c.listen_s);
    case Subcommand::Record: return cmd_record(c.bus, c.record);
    case Subcommand::Play: return cmd_play(c.bus, c.play);
    case Subcommand::Hz:
    case Subcommand::Bw: {
      bus::Participant dds{c.bus.domain, c.bus.dds_config, {c.bus.secure_dir, c.bus.identity}};
      const auto last = watch_rate(dds, *bus::find_topic(c.topic), c.subcommand == Subcommand::Bw, c.window,
                                   std::chrono::milliseconds(static_cast<long long>(c.rate_duration_s * 1000)));
      return last ? common::kExitOk : common::kExitFailure;
    }
    case Subcommand::Echo: break;
  }
  auto echo_options = c.echo;
  echo_options.timeout = std::chrono::milliseconds(static_cast<long long>(c.timeout_s * 1000));
  try {
    const auto n = echo(bus::Participant{c.bus.domain, c.bus.dds_config, {c.bus.secure_dir, c.bus.identity}}, c.topic, echo_options);
    return echo_options.count > 0 && n < echo_options.count ? common::kExitFailure : common::kExitOk;
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi echo: " << e.what() << '\n';
    return common::kExitUsage;
  }
}

}  // namespace tachi::launcher
