#include "cli.hpp"

#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/launcher/config.hpp"

#include <fmt/format.h>

#include <iostream>
#include <utility>

namespace tachi::launcher {

int parse_command(int argc, char** argv, Command& c) {
  CLI::App app{"tachi: cut a virtual cloth with your hand. `tachi run` starts the whole pipeline; "
               "`tachi topics|echo|hz|bw|status` show what is on the DDS bus; `tachi record|play` record and replay it (MCAP)"};
  app.name("tachi");
  app.require_subcommand(1);
  std::string log_level;
  common::add_log_level_flag(app, log_level);

  RunFlags& f = c.run;
  // The defaults the help shows are the config's own (a flag unset leaves the config's value), so they cannot
  // drift from what a run uses: --print-config shows the same.
  const RunConfig defaults;
  auto* run = app.add_subcommand("run", "Start the pipeline (sensor, filter, sim, viewer; voice with a voice source) and supervise it");
  run->add_option("--config", f.config_file, "JSON file with any of the options below (flags override it)")->check(CLI::ExistingFile);
  run->add_flag("--print-config", f.print_config, "Print the effective config (defaults, --config, flags) as JSON and exit");
  auto* rec = run->add_option("--recording", f.recording, "Play this fakenect recording folder")->check(CLI::ExistingDirectory);
  run->add_flag("--live", f.live, "Use the live Kinect (the default without --recording)")->excludes(rec);
  run->add_flag("--mouse", f.mouse, "Cut with the mouse in the viewer's window (seed 001's blade): sim and viewer only")
      ->excludes(rec);
  run->add_option("--rate", f.rate, "Recording pace: real (=1), max or a factor (tachi-sensor --rate)")->default_str(defaults.rate);
  run->add_option("--gate", f.gate, "What opens a stroke (voice and either need --voice-wav or --voice-device)")
      ->check(CLI::IsMember({"threshold", "voice", "either"}))
      ->default_str(defaults.gate);
  auto* wav = run->add_option("--voice-wav", f.voice_wav, "Voice commands from a WAV file (starts tachi-voice)")->check(CLI::ExistingFile);
  run->add_option("--voice-device", f.voice_device, "Voice commands from an ALSA capture device (starts tachi-voice)")->excludes(wav);
  run->add_option("--blade", f.blade,
                  "tachi-sim --blade (razor, scalpel, utility, kitchen, hunting, worn; default: the simulator's, scalpel)");
  run->add_option("--grid", f.grid, "Cloth particles per side")->check(CLI::Range(2, 1024))->default_str(std::to_string(defaults.grid));
  run->add_option("--domain", f.domain, "DDS domain id of this pipeline")
      ->check(CLI::Range(0u, 232u))
      ->default_str(std::to_string(defaults.domain));
  run->add_option("--dds-config", f.dds_config, "Cyclone DDS XML for every node (default: loopback only)")->check(CLI::ExistingFile);
  run->add_option("--lossy", f.lossy,
                  "Test a lossy link: every node drops PERMILLE of 1000 packets it sends (Cyclone's transmit loss), "
                  "with retransmission timing for such a link")
      ->check(CLI::Range(0, kMaxLossyPermille))
      ->default_str(std::to_string(defaults.lossy_permille));
  run->add_option("--secure", f.secure, "DDS Security folder (scripts/make_test_pki.sh) for every node; each uses its own identity")
      ->check(CLI::ExistingDirectory);
  run->add_option("--out", f.out, "Output folder (summary.json, cloth.obj, plots, logs)")->default_str(defaults.out);
  run->add_flag("--headless,!--window", f.headless, "Viewer without a window (default when DISPLAY is unset)");
  run->add_flag("--in-process", f.in_process,
                "The nodes in one process (tachi-pipeline), each on its own thread and participant, as ROS 2 composes "
                "components; same nodes, same bus, no process isolation");
  run->add_option("--nodes", f.nodes,
                  "Start only these nodes, e.g. sensor,filter (the other host runs sim,viewer); default sensor,filter,sim,viewer "
                  "(sim,viewer with --mouse), and voice with a voice source");
  run->add_option("--settle", f.settle_s, "With a recording: end this many seconds after the last hand sample")
      ->check(CLI::Range(0.1, 60.0))
      ->default_str(fmt::format("{:g}", defaults.settle_s));
  run->add_option("--run-id", f.run_id, "DDS partition of this run's nodes (default: a fresh one; none with --nodes)");
  run->add_option("--set", f.sets, "NODE.FLAG=VALUE passed to one node, e.g. sim.material=denim (repeatable)");
  auto* record_flag = run->add_flag("--record", f.record, "Record the run's whole bus into <out>/run.mcap (as `tachi record`)");
  run->add_flag("--foxglove", f.foxglove, "With --record: add the Foxglove channels (as `tachi record --foxglove`)")->needs(record_flag);

  auto& bus = c.bus;
  bus.identity = "monitor";  // with --secure: the identity that may read every topic (scripts/make_test_pki.sh)
  auto& listen_s = c.listen_s;
  auto* topics = app.add_subcommand("topics", "List the participants (process, host, pid) and topics (type, writers, readers) on a domain");
  common::add_bus_flags(*topics, bus);
  topics->add_option("--listen", listen_s, "Seconds to listen to discovery")->check(CLI::Range(0.1, 60.0))->capture_default_str();
  auto& verbose = c.verbose;
  topics->add_flag("--verbose,-v", verbose, "Show each writer's offered and each reader's requested QoS");

  auto& topic = c.topic;
  auto& echo_options = c.echo;
  auto& timeout_s = c.timeout_s;
  const auto is_known_topic = [](const std::string& t) {
    return known_topic(t) ? std::string{} : "unknown topic; known: " + bus::topic_names();
  };
  auto* echo = app.add_subcommand("echo", "Print a topic's samples as JSON lines");
  echo->add_option("topic", topic, "Topic, e.g. tachi/cloth/cut")->required()->check(is_known_topic);
  common::add_bus_flags(*echo, bus);
  echo->add_option("--count", echo_options.count, "Stop after this many samples (0: until SIGINT)");
  echo->add_flag("--full", echo_options.full, "Print long arrays whole instead of their length and first elements");
  echo->add_option("--field", echo_options.field, "Print only this field, a dotted path: e.g. position_m.2, metrics.fps, positions");
  echo->add_option("--timeout", timeout_s, "Stop after this many seconds (0: no limit)")->check(CLI::NonNegativeNumber);

  auto& window = c.window;
  auto& rate_duration_s = c.rate_duration_s;
  CLI::App* rate_tools[2];
  for (const bool bandwidth : {false, true}) {
    auto* sub = app.add_subcommand(bandwidth ? "bw" : "hz",
                                   bandwidth ? "Print a topic's bandwidth (bytes per second, message sizes) every second, like ros2 topic bw"
                                             : "Print a topic's rate and jitter every second, like ros2 topic hz");
    sub->add_option("topic", topic, "Topic, e.g. tachi/hand/raw")->required()->check(is_known_topic);
    sub->add_option("--window", window, "Figures over the last N samples")->check(CLI::Range(2, 1000000))->capture_default_str();
    sub->add_option("--duration", rate_duration_s, "Stop after S seconds (0: until SIGINT)")->check(CLI::NonNegativeNumber);
    common::add_bus_flags(*sub, bus);
    rate_tools[bandwidth] = sub;
  }

  auto* status = app.add_subcommand("status", "Show each node's latest heartbeat (state, counts, rejected inputs, figures)");
  common::add_bus_flags(*status, bus);
  status->add_option("--listen", listen_s, "Seconds to collect heartbeats")->check(CLI::Range(0.1, 60.0))->capture_default_str();

  auto& record_options = c.record;
  std::string record_file;
  auto* record = app.add_subcommand("record", "Record the bus into an MCAP file (omgidl schemas, CDR messages), until Ctrl-C");
  record->add_option("file", record_file, "The MCAP file to write, e.g. run.mcap")->required();
  record->add_option("--topics", record_options.topics, "Only these topics (comma separated; default: every tachi topic)")->delimiter(',');
  record->add_option("--duration", record_options.duration_s, "Stop after S seconds")->check(CLI::PositiveNumber);
  record->add_option("--max-bytes", record_options.max_bytes, "Stop before the file passes N bytes")->check(CLI::PositiveNumber);
  record->add_flag("--foxglove", record_options.foxglove,
                   "Add channels in Foxglove's schemas: /foxglove/cloth (SceneUpdate), /foxglove/hand (PoseInFrame), /foxglove/latency");
  auto& tool_run_id = c.tool_run_id;
  record->add_option("--run-id", tool_run_id, "Record only this run's samples (default: every run on the domain)");
  common::add_bus_flags(*record, bus);

  auto& play_options = c.play;
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
  common::add_bus_flags(*play, bus);

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
      return common::kExitUsage;
    }
  }
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  common::set_log_level(log_level);
  for (const auto* option : run->get_options())
    if (option->count() > 0) f.given.insert(option->get_name());
  record_options.file = record_file;
  play_options.file = play_file;
  const std::pair<const CLI::App*, Subcommand> subcommands[] = {{run, Subcommand::Run},       {topics, Subcommand::Topics},
                                                                {echo, Subcommand::Echo},     {rate_tools[0], Subcommand::Hz},
                                                                {rate_tools[1], Subcommand::Bw}, {status, Subcommand::Status},
                                                                {record, Subcommand::Record}, {play, Subcommand::Play}};
  for (const auto& [app_of, subcommand] : subcommands)
    if (app_of->parsed()) c.subcommand = subcommand;
  return -1;
}

}  // namespace tachi::launcher
