// libFuzzer target: the fakenect recording reader's two parsers of untrusted bytes, an INDEX.txt
// line and a depth PGM (docs/reliability.md, "Fuzzing"). Either returns an error or a frame of
// exactly 640 x 480 values within 11 bits; never a crash, a hang or an out-of-bounds read.
#include "tachi/sensor/fakenect_recording.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::string why;
  if (const auto entry = tachi::sensor::parse_index_line(text, &why)) {
    if (entry->host_time_ns < 0 || entry->file.empty()) std::abort();
  } else if (why.empty()) {
    std::abort();  // a refusal always says why
  }
  std::vector<std::uint16_t> raw;
  const auto result = tachi::sensor::decode_depth_pgm({text.data(), text.size()}, raw);
  if (std::holds_alternative<std::monostate>(result)) {
    if (raw.size() != static_cast<std::size_t>(tachi::sensor::kDepthPixels)) std::abort();
    for (const auto v : raw)
      if (v > tachi::sensor::kNoReading) std::abort();
  }
  return 0;
}
