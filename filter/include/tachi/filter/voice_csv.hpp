// tachi-voice's printed output (time_s,command,phrase per line), read back to replay voice gating offline.
#pragma once

#include "tachi/filter/types.hpp"

#include <istream>
#include <string>
#include <vector>

namespace tachi::filter {

struct TimedCommand {
  double time_s;
  VoiceCommandKind kind;
};

struct VoiceCsv {
  std::vector<TimedCommand> commands;  ///< sorted by time (stable: same-time commands keep their order)
  std::vector<std::string> skipped;    ///< "line N: why" per row that was not a command
};

/// Reads time_s,start|stop|grab|release[,phrase] rows; a header row ("time_s...") and empty lines are ignored.
[[nodiscard]] VoiceCsv read_voice_csv(std::istream& in);

}  // namespace tachi::filter
