// tachi: the one command. `tachi run` starts and supervises the pipeline's processes and leaves the
// run's outputs in a folder; `tachi topics|echo|hz|bw|status` show what is on a domain's bus and
// `tachi record|play` record it into MCAP and publish it again (docs/cli.md "tachi").
#include "src/bus_adapter.hpp"
#include "src/preflight.hpp"
#include "src/record.hpp"
#include "src/run.hpp"
#include "tachi/common/disk_full.hpp"
#include "tachi/bus/discovery.hpp"
#include "tachi/bus/run_partition.hpp"
#include "tachi/common/app.hpp"
#include "tachi/launcher/config.hpp"
#include "tachi/launcher/supervision.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

namespace {
namespace fs = std::filesystem;
namespace launcher = tachi::launcher;
using nlohmann::json;

struct RunFlags {
  std::string config_file, recording, rate, gate, voice_wav, voice_device, blade, out, nodes, dds_config, secure, run_id;
  bool live = false, headless = false, print_config = false, mouse = false, record = false, foxglove = false;
  int grid = 0;
  unsigned domain = 0;
  double settle_s = 0;
  std::vector<std::string> sets;
};

fs::path self_dir(const char* argv0) {
  std::error_code ec;
  const auto exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::absolute(argv0).parent_path() : exe.parent_path();
}

// Defaults, then the config file, then the flags that were given, then --set.
json effective_config(const CLI::App& run, const RunFlags& f) {
  json config = launcher::default_config_json(std::getenv("DISPLAY") != nullptr && *std::getenv("DISPLAY") != '\0');
  if (!f.config_file.empty()) {
    std::ifstream in(f.config_file);
    json file = json::parse(in, nullptr, false);
    if (file.is_discarded() || !file.is_object()) throw std::invalid_argument("--config " + f.config_file + ": not a JSON object");
    launcher::merge_into(config, file);
  }
  const auto given = [&](const char* flag) { return run.count(flag) > 0; };
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
  if (given("--secure")) config["secure"] = fs::absolute(f.secure).string();
  if (given("--out")) config["out"] = f.out;
  if (given("--headless")) config["headless"] = f.headless;
  if (given("--nodes")) config["nodes"] = f.nodes;
  if (given("--settle")) config["settle_s"] = f.settle_s;
  if (given("--mouse")) config["mouse"] = f.mouse;
  for (const auto& s : f.sets) launcher::merge_into(config, launcher::parse_set(s));
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
std::string live_pipeline_nodes(const launcher::RunConfig& config) {
  tachi::bus::Participant dds{config.domain, config.dds_config, {config.secure, "monitor"}};
  const auto snapshot = tachi::bus::discover(dds, std::chrono::milliseconds(500));
  std::string live;
  for (const auto& p : snapshot.participants) {
    if (p.self || !p.process.starts_with("tachi-") || !config.has(p.process.substr(6))) continue;
    live += (live.empty() ? "" : ", ") + p.process + " on host " + p.host + ", pid " + p.pid;
  }
  return live;
}

int cmd_run(const CLI::App& run, const RunFlags& f, const fs::path& bin_dir) {
  launcher::RunConfig config;
  json effective;
  try {
    effective = effective_config(run, f);
    config = launcher::from_json(effective);
  } catch (const std::exception& e) {
    std::cerr << "tachi run: " << e.what() << '\n';
    return launcher::kRunUsage;
  }
  if (f.print_config) {
    std::cout << launcher::to_json(config).dump(2) << '\n';
    return launcher::kRunOk;
  }
  if (!config.recording.empty() && !fs::exists(fs::path(config.recording) / "INDEX.txt")) {
    std::cerr << "tachi run: --recording " << config.recording << ": not a fakenect recording (no INDEX.txt)\n";
    return launcher::kRunUsage;
  }
  if (!config.recording.empty()) config.recording = fs::absolute(config.recording).string();
  // Before any node starts: a mistake is named now, and no headline follows that could pass for a run.
  auto error = launcher::check_out_folder(config, launcher::estimate_output_bytes(config));
  if (!error) error = launcher::check_node_flags(config, bin_dir);
  if (error) {
    std::cerr << "tachi run: " << error->message << '\n';
    return error->exit_code;
  }
  tachi::common::install_stop_handlers();
  // The run id names the DDS partition of every node of this run (bus/run_partition.hpp), passed down in
  // the environment. A whole pipeline gets a fresh one; one split over launchers (--nodes) shares the
  // default partition unless each is given the same --run-id; DDS Security grants name no partitions
  // (scripts/make_test_pki.sh), so a secure run stays in the default one too.
  std::string run_id = f.run_id;
  if (run_id.empty() && !run.count("--nodes") && config.secure.empty())
    run_id = fmt::format("{:016x}", tachi::bus::new_session_id());
  if (!run_id.empty()) ::setenv(tachi::bus::kRunIdEnv, run_id.c_str(), 1);
  else ::unsetenv(tachi::bus::kRunIdEnv);
  if (const auto live = live_pipeline_nodes(config); !live.empty()) {
    std::cerr << "tachi run: DDS domain " << config.domain << " already has a live tachi pipeline: " << live
              << "; two pipelines on one domain would mix their samples. Stop it, or give this run another --domain\n";
    return launcher::kRunFailure;
  }
  if (!f.record) {
    std::error_code ignored;
    fs::remove(fs::path(config.out) / "run.mcap", ignored);  // a previous run's recording must not pass for this run's
    const int rc = launcher::run(config, {bin_dir, fs::path(TACHI_SCRIPTS_DIR) / "plot_run.py"});
    add_to_summary(config.out, {{"run_id", run_id}});
    return rc;
  }

  // --record: the whole bus of the run into <out>/run.mcap, from before the first node starts until
  // the last one stopped; the recorder's own figures join summary.json.
  const fs::path out(config.out);
  fs::create_directories(out);
  tachi::bus::Participant dds{config.domain, config.dds_config, {config.secure, "monitor"}};
  launcher::RecordOptions record_options;
  record_options.file = out / "run.mcap";
  record_options.foxglove = f.foxglove;
  launcher::BackgroundRecorder recorder{dds, record_options};
  const int rc = launcher::run(config, {bin_dir, fs::path(TACHI_SCRIPTS_DIR) / "plot_run.py"});
  const auto recorded = recorder.stop();
  spdlog::info("recorded {} messages ({} lost) into {}", recorded.total, recorded.lost, (out / "run.mcap").string());
  add_to_summary(out, {{"run_id", run_id},
                       {"recording", {{"file", "run.mcap"}, {"messages", recorded.messages}, {"lost", recorded.lost}, {"bytes", recorded.bytes},
                                     {"ended", recorded.ended}}}});
  return rc;
}

int cmd_record(const tachi::common::BusOptions& bus, const launcher::RecordOptions& options) {
  if (const auto unknown = launcher::unknown_topics(options.topics); !unknown.empty()) {
    std::cerr << "tachi record: --topics: unknown topic " << unknown.front() << "; known: " << tachi::bus::topic_names() << '\n';
    return tachi::common::kExitUsage;
  }
  tachi::bus::Participant dds{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}};
  launcher::Recorder recorder{dds, options};
  spdlog::info("recording domain {} into {} (Ctrl-C stops)", bus.domain, options.file.string());
  while (!tachi::common::stop_requested() && recorder.poll(std::chrono::milliseconds(100))) {
  }
  const auto r = recorder.finish("stopped by signal");
  std::cout << json{{"file", options.file.string()}, {"messages", r.total}, {"topics", r.messages}, {"lost", r.lost},
                    {"bytes", r.bytes}, {"ended", r.ended}}
                   .dump()
            << '\n';
  return tachi::common::kExitOk;
}

int cmd_play(const tachi::common::BusOptions& bus, const launcher::PlayOptions& options) {
  if (const auto unknown = launcher::unknown_topics(options.topics); !unknown.empty()) {
    std::cerr << "tachi play: --topics: unknown topic " << unknown.front() << "; known: " << tachi::bus::topic_names() << '\n';
    return tachi::common::kExitUsage;
  }
  tachi::bus::Participant dds{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}};
  const auto r = launcher::play(dds, options);
  std::cout << json{{"file", options.file.string()}, {"published", r.published}, {"skipped", r.skipped}}.dump() << '\n';
  return tachi::common::kExitOk;
}

int cmd_topics(const tachi::common::BusOptions& bus, double listen_s, bool verbose) {
  tachi::bus::Participant dds{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}};
  const auto snapshot = tachi::bus::discover(dds, std::chrono::milliseconds(static_cast<int>(listen_s * 1000)));
  std::map<std::string, const tachi::bus::ParticipantInfo*> by_key;
  std::cout << "participants on domain " << bus.domain << ":\n";
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
  return tachi::common::kExitOk;
}

int cmd_status(const tachi::common::BusOptions& bus, double listen_s) {
  tachi::bus::Participant dds{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}};
  tachi::bus::Reader<tachi_msg_NodeStatus> reader{dds, tachi::bus::topics::node_status};
  launcher::StatusBoard board;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(listen_s);
  // Transient-local: each node's latest heartbeat arrives as soon as it is discovered.
  while (std::chrono::steady_clock::now() < deadline && !tachi::common::stop_requested()) {
    reader.wait_for_data(std::chrono::milliseconds(100));
    for (const auto& s : reader.take()) board.update(launcher::from_msg(*s));
  }
  if (board.nodes().empty()) {
    std::cout << "no heartbeats on domain " << bus.domain << '\n';
    return tachi::common::kExitFailure;
  }
  for (const auto& [name, r] : board.nodes()) {
    std::cout << name << "  host " << r.host << "  pid " << r.pid << "  " << r.state << "  in " << r.messages_in << "  out "
              << r.messages_out << "  rejected " << r.rejected << (r.detail.empty() ? "" : "  \"" + r.detail + "\"") << '\n';
    for (const auto& [metric, value] : r.metrics) std::cout << "    " << metric << " " << value << '\n';
  }
  std::cout << board.line(0) << '\n';
  return tachi::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi: cut a virtual cloth with your hand. `tachi run` starts the whole pipeline; "
               "`tachi topics|echo|hz|bw|status` show what is on the DDS bus; `tachi record|play` record and replay it (MCAP)"};
  app.name("tachi");
  app.require_subcommand(1);
  std::string log_level;
  tachi::common::add_log_level_flag(app, log_level);

  RunFlags f;
  auto* run = app.add_subcommand("run", "Start the pipeline (sensor, filter, sim, viewer; voice with a voice source) and supervise it");
  run->add_option("--config", f.config_file, "JSON file with any of the options below (flags override it)")->check(CLI::ExistingFile);
  run->add_flag("--print-config", f.print_config, "Print the effective config (defaults, --config, flags) as JSON and exit");
  auto* rec = run->add_option("--recording", f.recording, "Play this fakenect recording folder")->check(CLI::ExistingDirectory);
  run->add_flag("--live", f.live, "Use the live Kinect (the default without --recording)")->excludes(rec);
  run->add_flag("--mouse", f.mouse, "Cut with the mouse in the viewer's window (seed 001's blade): sim and viewer only")
      ->excludes(rec);
  run->add_option("--rate", f.rate, "Recording pace: real (=1), max or a factor (tachi-sensor --rate)");
  run->add_option("--gate", f.gate, "What opens a stroke")->check(CLI::IsMember({"threshold", "voice", "either"}));
  auto* wav = run->add_option("--voice-wav", f.voice_wav, "Voice commands from a WAV file (starts tachi-voice)")->check(CLI::ExistingFile);
  run->add_option("--voice-device", f.voice_device, "Voice commands from an ALSA capture device (starts tachi-voice)")->excludes(wav);
  run->add_option("--blade", f.blade, "tachi-sim --blade (razor, scalpel, utility, kitchen, hunting, worn)");
  run->add_option("--grid", f.grid, "Cloth particles per side")->check(CLI::Range(2, 1024));
  run->add_option("--domain", f.domain, "DDS domain id of this pipeline")->check(CLI::Range(0u, 232u));
  run->add_option("--dds-config", f.dds_config, "Cyclone DDS XML for every node (default: loopback only)")->check(CLI::ExistingFile);
  run->add_option("--secure", f.secure, "DDS Security folder (scripts/make_test_pki.sh) for every node; each uses its own identity")
      ->check(CLI::ExistingDirectory);
  run->add_option("--out", f.out, "Output folder (summary.json, cloth.obj, plots, logs); default out/run");
  run->add_flag("--headless,!--window", f.headless, "Viewer without a window (default when DISPLAY is unset)");
  run->add_option("--nodes", f.nodes, "Start only these nodes, e.g. sensor,filter (the other host runs sim,viewer)");
  run->add_option("--settle", f.settle_s, "With a recording: end this many seconds after the last hand sample")
      ->check(CLI::Range(0.1, 60.0));
  run->add_option("--run-id", f.run_id, "DDS partition of this run's nodes (default: a fresh one; none with --nodes or --secure)");
  run->add_option("--set", f.sets, "NODE.FLAG=VALUE passed to one node, e.g. sim.material=denim (repeatable)");
  auto* record_flag = run->add_flag("--record", f.record, "Record the run's whole bus into <out>/run.mcap (as `tachi record`)");
  run->add_flag("--foxglove", f.foxglove, "With --record: add the Foxglove channels (as `tachi record --foxglove`)")->needs(record_flag);

  tachi::common::BusOptions bus;
  bus.identity = "monitor";  // with --secure: the identity that may read every topic (scripts/make_test_pki.sh)
  double listen_s = 1.5;
  auto* topics = app.add_subcommand("topics", "List the participants (process, host, pid) and topics (type, writers, readers) on a domain");
  tachi::common::add_bus_flags(*topics, bus);
  topics->add_option("--listen", listen_s, "Seconds to listen to discovery")->check(CLI::Range(0.1, 60.0))->capture_default_str();
  bool verbose = false;
  topics->add_flag("--verbose,-v", verbose, "Show each writer's offered and each reader's requested QoS");

  std::string topic;
  launcher::EchoOptions echo_options;
  double timeout_s = 0;
  const auto known_topic = [](const std::string& t) {
    return launcher::known_topic(t) ? std::string{} : "unknown topic; known: " + tachi::bus::topic_names();
  };
  auto* echo = app.add_subcommand("echo", "Print a topic's samples as JSON lines");
  echo->add_option("topic", topic, "Topic, e.g. tachi/cloth/cut")->required()->check(known_topic);
  tachi::common::add_bus_flags(*echo, bus);
  echo->add_option("--count", echo_options.count, "Stop after this many samples (0: until SIGINT)");
  echo->add_flag("--full", echo_options.full, "Print long arrays whole instead of their length and first elements");
  echo->add_option("--field", echo_options.field, "Print only this field, a dotted path: e.g. position_m.2, metrics.fps, positions");
  echo->add_option("--timeout", timeout_s, "Stop after this many seconds (0: no limit)")->check(CLI::NonNegativeNumber);

  std::size_t window = 10000;
  double rate_duration_s = 0;
  CLI::App* rate_tools[2];
  for (const bool bandwidth : {false, true}) {
    auto* sub = app.add_subcommand(bandwidth ? "bw" : "hz",
                                   bandwidth ? "Print a topic's bandwidth (bytes per second, message sizes) every second, like ros2 topic bw"
                                             : "Print a topic's rate and jitter every second, like ros2 topic hz");
    sub->add_option("topic", topic, "Topic, e.g. tachi/hand/raw")->required()->check(known_topic);
    sub->add_option("--window", window, "Figures over the last N samples")->check(CLI::Range(2, 1000000))->capture_default_str();
    sub->add_option("--duration", rate_duration_s, "Stop after S seconds (0: until SIGINT)")->check(CLI::NonNegativeNumber);
    tachi::common::add_bus_flags(*sub, bus);
    rate_tools[bandwidth] = sub;
  }

  auto* status = app.add_subcommand("status", "Show each node's latest heartbeat (state, counts, rejected inputs, figures)");
  tachi::common::add_bus_flags(*status, bus);
  status->add_option("--listen", listen_s, "Seconds to collect heartbeats")->check(CLI::Range(0.1, 60.0))->capture_default_str();

  launcher::RecordOptions record_options;
  std::string record_file;
  auto* record = app.add_subcommand("record", "Record the bus into an MCAP file (omgidl schemas, CDR messages), until Ctrl-C");
  record->add_option("file", record_file, "The MCAP file to write, e.g. run.mcap")->required();
  record->add_option("--topics", record_options.topics, "Only these topics (comma separated; default: every tachi topic)")->delimiter(',');
  record->add_option("--duration", record_options.duration_s, "Stop after S seconds")->check(CLI::PositiveNumber);
  record->add_option("--max-bytes", record_options.max_bytes, "Stop before the file passes N bytes")->check(CLI::PositiveNumber);
  record->add_flag("--foxglove", record_options.foxglove,
                   "Add channels in Foxglove's schemas: /foxglove/cloth (SceneUpdate), /foxglove/hand (PoseInFrame), /foxglove/latency");
  std::string tool_run_id;
  record->add_option("--run-id", tool_run_id, "Record only this run's samples (default: every run on the domain)");
  tachi::common::add_bus_flags(*record, bus);

  launcher::PlayOptions play_options;
  std::string play_file;
  auto* play = app.add_subcommand("play", "Publish an MCAP recording's tachi topics again with their recorded timing");
  play->add_option("file", play_file, "The MCAP file, e.g. out/run/run.mcap")->required()->check(CLI::ExistingFile);
  play->add_option("--rate", play_options.rate, "Speed factor (2: twice as fast)")->check(CLI::Range(1e-3, 1e3))->capture_default_str();
  play->add_flag("--loop", play_options.loop, "Play again from the start until Ctrl-C");
  play->add_option("--topics", play_options.topics, "Only these topics (comma separated; default: every tachi topic)")->delimiter(',');
  play->add_option("--start", play_options.start_s, "Skip the recording's first S seconds")->check(CLI::NonNegativeNumber);
  play->add_option("--wait", play_options.wait_s, "Wait up to S seconds for a reader of every played topic before starting")
      ->check(CLI::Range(0.0, 600.0));
  play->add_option("--run-id", tool_run_id, "Publish into this run's partition (tachi run --run-id; default: the default partition)");
  tachi::common::add_bus_flags(*play, bus);

  // CLI11 answers an unknown subcommand with "A subcommand is required": name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    const std::string given = argv[1];
    std::string known;
    bool found = false;
    for (const auto* sub : app.get_subcommands({})) {
      known += (known.empty() ? "" : ", ") + sub->get_name();
      found = found || sub->check_name(given);
    }
    if (!found) {
      std::cerr << "tachi: unknown subcommand " << given << "; known: " << known << '\n';
      return tachi::common::kExitUsage;
    }
  }
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(log_level);

  if (run->parsed()) return cmd_run(*run, f, self_dir(argv[0]));
  tachi::common::install_stop_handlers();
  // Bus tools read every run's partition; record and play may name one run.
  if (!tool_run_id.empty()) ::setenv(tachi::bus::kRunIdEnv, tool_run_id.c_str(), 1);
  else if (!play->parsed()) tachi::bus::read_every_run();
  if (topics->parsed()) return cmd_topics(bus, listen_s, verbose);
  if (status->parsed()) return cmd_status(bus, listen_s);
  if (record->parsed()) {
    record_options.file = record_file;
    return cmd_record(bus, record_options);
  }
  if (play->parsed()) {
    play_options.file = play_file;
    return cmd_play(bus, play_options);
  }
  if (rate_tools[0]->parsed() || rate_tools[1]->parsed()) {
    tachi::bus::Participant dds{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}};
    const auto last = launcher::watch_rate(dds, *tachi::bus::find_topic(topic), rate_tools[1]->parsed(), window,
                                           std::chrono::milliseconds(static_cast<long long>(rate_duration_s * 1000)));
    return last ? tachi::common::kExitOk : tachi::common::kExitFailure;
  }
  echo_options.timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
  try {
    const auto n = launcher::echo(tachi::bus::Participant{bus.domain, bus.dds_config, {bus.secure_dir, bus.identity}}, topic, echo_options);
    return echo_options.count > 0 && n < echo_options.count ? tachi::common::kExitFailure : tachi::common::kExitOk;
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi echo: " << e.what() << '\n';
    return tachi::common::kExitUsage;
  }
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi: " << e.what() << '\n';
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
