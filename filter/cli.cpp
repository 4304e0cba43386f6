#include "cli.hpp"

#include <iostream>

namespace tachi::filter {

int parse_flags(int argc, char** argv, Flags& flags) {
  CLI::App app{"tachi-filter: smooths raw hand samples, maps them onto the cloth and gates cutting strokes"};
  app.name("tachi-filter");
  auto& o = flags.offline_options;
  std::string config_file, smoother, gate, log_level;
  bool print_config = false;
  app.add_flag("--offline", flags.offline, "Read a hand CSV and write a stroke CSV instead of joining the DDS bus");
  app.add_option("--hands", o.hands_csv, "Offline input: the sensor's CSV (frame,stamp_ns,x,y,z,u,v,tracked,confidence)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", o.out_csv, "Offline output: frame,stamp_ns,x,y,z,gate,stroke_id");
  app.add_option("--voice", o.voice_csv,
                 "Offline: voice commands as tachi-voice prints them (time_s,command,phrase; time 0 = first hand sample)")
      ->check(CLI::ExistingFile);
  app.add_option("--config", config_file, "Filter config JSON (see config/filter.json); defaults built in")
      ->check(CLI::ExistingFile);
  app.add_option("--smoother", smoother, "Override the config's smoother")
      ->check(CLI::IsMember({"wiener-bank", "wiener", "one-euro", "moving-average", "none"}));
  app.add_option("--gate", gate, "Override the config's gate mode")->check(CLI::IsMember({"threshold", "voice", "either"}));
  app.add_flag("--camera-frame", o.camera_frame, "Offline: write camera-frame positions instead of world-frame ones");
  app.add_flag("--print-config", print_config, "Print the effective config as JSON and exit");
  app.add_option("--journal", flags.journal,
                 "Journal every hand sample and voice command to this file; started again with the same file, the "
                 "filter replays it and carries the open stroke on under the same session (tachi run passes it)");
  common::add_log_level_flag(app, log_level);
  common::add_bus_flags(app, flags.bus);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  // Logs go to stderr: stdout carries the command lines (tachi-voice) and must stay parseable.
  common::set_log_level(log_level);

  try {
    if (!config_file.empty()) flags.config = load_filter_config(config_file);
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi-filter: --config " << config_file << ": " << e.what() << '\n';
    return common::kExitUsage;
  }
  if (!smoother.empty()) flags.config.smoother.kind = *smoother_kind_from_string(smoother);
  if (!gate.empty()) flags.config.gate.mode = *gate_mode_from_string(gate);
  if (print_config) {
    std::cout << to_json(flags.config) << '\n';
    return common::kExitOk;
  }
  if (flags.offline) {
    if (!flags.journal.empty()) {
      std::cerr << "tachi-filter: --journal is for the DDS filter, not --offline\n";
      return common::kExitUsage;
    }
    if (o.hands_csv.empty() || o.out_csv.empty()) {
      std::cerr << "tachi-filter: --offline needs --hands IN.csv and --out OUT.csv\n";
      return common::kExitUsage;
    }
  } else if (!o.hands_csv.empty() || !o.out_csv.empty() || !o.voice_csv.empty() || o.camera_frame) {
    std::cerr << "tachi-filter: --hands, --out, --voice and --camera-frame need --offline\n";
    return common::kExitUsage;
  }
  return -1;
}

}  // namespace tachi::filter
