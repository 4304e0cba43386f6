// `tachi`'s command line: the subcommands (run, topics, echo, hz, bw, status, record, play) and their flags,
// registered here by the executable; commands.cpp runs the one that was given.
#pragma once

#include "bus_adapter.hpp"
#include "record.hpp"
#include "tachi/common/exit_codes.hpp"
#include "tachi/common/process.hpp"

#include <set>
#include <string>
#include <vector>

namespace tachi::launcher {

/// `tachi run`'s flags, and which of them were given (they override the config file; the others do not).
struct RunFlags {
  std::string config_file, recording, rate, gate, voice_wav, voice_device, blade, out, nodes, dds_config, secure, run_id;
  bool live = false, headless = false, print_config = false, mouse = false, record = false, foxglove = false, in_process = false;
  int grid = 0, lossy = 0;
  unsigned domain = 0;
  double settle_s = 0;
  std::vector<std::string> sets;
  std::set<std::string> given;  ///< the long names ("--recording") of the flags on the command line
  [[nodiscard]] bool has(const std::string& flag) const { return given.count(flag) > 0; }
};

enum class Subcommand { Run, Topics, Echo, Hz, Bw, Status, Record, Play };

/// One parsed command line: the subcommand and every subcommand's options (only its own are set).
struct Command {
  Subcommand subcommand = Subcommand::Run;
  RunFlags run;
  common::BusOptions bus;  ///< the bus tools' --domain, --dds-config, --secure, --identity
  double listen_s = 1.5;   ///< topics, status
  bool verbose = false;    ///< topics
  std::string topic;       ///< echo, hz, bw
  EchoOptions echo;
  double timeout_s = 0;    ///< echo
  std::size_t window = 10000;   ///< hz, bw
  double rate_duration_s = 0;   ///< hz, bw
  RecordOptions record;
  PlayOptions play;
  std::string tool_run_id;  ///< record, play
};

/// Parses argv (an unknown subcommand is named with the known ones) and applies --log-level. An exit code
/// when the process should stop now (help: 0; a bad flag: kExitUsage naming it), else -1.
int parse_command(int argc, char** argv, Command& command);

}  // namespace tachi::launcher
