#include "tachi/filter/voice_csv.hpp"

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <sstream>

namespace tachi::filter {
namespace {
std::optional<VoiceCommandKind> command_kind(const std::string& name) {
  if (name == "start") return VoiceCommandKind::Start;
  if (name == "stop") return VoiceCommandKind::Stop;
  if (name == "grab") return VoiceCommandKind::Grab;
  if (name == "release") return VoiceCommandKind::Release;
  return std::nullopt;
}
}  // namespace

VoiceCsv read_voice_csv(std::istream& in) {
  VoiceCsv csv;
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
    const auto kind = command_kind(command);
    if (end == time.c_str() || !kind) {
      csv.skipped.push_back("line " + std::to_string(line_no) + ": expected time_s,start|stop|grab|release,phrase");
      continue;
    }
    csv.commands.push_back({t, *kind});
  }
  std::stable_sort(csv.commands.begin(), csv.commands.end(), [](const auto& a, const auto& b) { return a.time_s < b.time_s; });
  return csv;
}

}  // namespace tachi::filter
