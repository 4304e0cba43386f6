// libFuzzer target: the config readers of untrusted text: the filter's JSON config and the hand CSV
// tachi-filter --offline reads. A bad config is a std::invalid_argument naming the field, a hand CSV
// without its header a std::runtime_error (the documented errors); never another exception or a crash.
#include "tachi/filter/config.hpp"
#include "tachi/filter/hand_csv.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto config = tachi::filter::parse_filter_config(text);
    // A config that parsed serialises and parses back to itself.
    const auto again = tachi::filter::parse_filter_config(tachi::filter::to_json(config));
    if (tachi::filter::to_json(again) != tachi::filter::to_json(config)) std::abort();
  } catch (const std::invalid_argument&) {
    // the documented refusal
  }
  std::istringstream in(text);
  try {
    const auto hands = tachi::filter::read_hand_csv(in);
    for (const auto& h : hands.samples)
      if (h.tracked && !h.position_m.allFinite()) std::abort();
  } catch (const std::runtime_error&) {
    // the documented refusal of a file without the header
  }
  return 0;
}
