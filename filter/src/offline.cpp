// The offline filter: a hand CSV (and tachi-voice's command lines) through the same StrokeFilter as the bus.
#include "tachi/common/app.hpp"
#include "tachi/filter/hand_csv.hpp"
#include "tachi/filter/node.hpp"
#include "tachi/filter/stroke_filter.hpp"
#include "tachi/filter/voice_csv.hpp"

#include <spdlog/spdlog.h>

#include <fstream>
#include <stdexcept>

namespace tachi::filter {
namespace {
std::vector<TimedCommand> load_voice_csv(const std::string& path) {
  if (path.empty()) return {};
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read voice commands " + path);
  auto csv = read_voice_csv(in);
  for (const auto& why : csv.skipped) spdlog::warn("{} {}; skipped", path, why);
  return std::move(csv.commands);
}
}  // namespace

int run_offline(const OfflineFilterOptions& o, const FilterConfig& config) {
  std::ifstream in(o.hands_csv);
  if (!in) throw std::runtime_error("cannot read " + o.hands_csv);
  const auto hands = read_hand_csv(in);
  for (const auto& why : hands.skipped) spdlog::warn("{}: {}; row skipped", o.hands_csv, why);
  const auto commands = load_voice_csv(o.voice_csv);

  std::ofstream out(o.out_csv);
  if (!out) throw std::runtime_error("cannot write " + o.out_csv);
  StrokeFilter filter{config};
  write_stroke_csv_header(out);
  std::size_t next_command = 0;
  const std::int64_t t0 = hands.samples.empty() ? 0 : hands.samples.front().stamp_ns;
  std::uint32_t strokes = 0;
  for (const auto& hand : hands.samples) {
    // Voice time 0 is the first hand sample: the recording's audio track starts with its video.
    const double t = static_cast<double>(hand.stamp_ns - t0) * 1e-9;
    while (next_command < commands.size() && commands[next_command].time_s <= t) {
      if (const auto why = filter.on_voice(commands[next_command++].kind)) spdlog::warn("{}", *why);
    }
    const auto stroke = filter.on_hand(hand);
    strokes = stroke.stroke_id;
    write_stroke_csv_row(out, stroke, o.camera_frame);
  }
  out.flush();
  if (!out) throw std::runtime_error("write failed: " + o.out_csv);
  spdlog::info("{} samples ({} skipped, {} outliers), {} strokes -> {}", hands.samples.size(), hands.skipped.size(),
               filter.outliers(), strokes, o.out_csv);
  return common::kExitOk;
}

}  // namespace tachi::filter
