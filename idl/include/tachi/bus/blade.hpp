// The names of tachi.idl's Blade values (seed 001 Figure 4), for readers that show which blade tachi-sim cuts
// with (the viewer's HUD) without linking the simulator: the enum, not tachi_sim, is the contract.
#pragma once

#include "tachi.h"

#include <cmath>
#include <optional>
#include <string_view>

namespace tachi::bus {

/// "razor", "scalpel", "utility", "kitchen", "hunting", "worn" (tachi-sim's --blade names).
[[nodiscard]] constexpr std::optional<std::string_view> blade_name(tachi_msg_Blade blade) {
  switch (blade) {
    case tachi_msg_BLADE_RAZOR: return "razor";
    case tachi_msg_BLADE_SCALPEL: return "scalpel";
    case tachi_msg_BLADE_UTILITY: return "utility";
    case tachi_msg_BLADE_KITCHEN: return "kitchen";
    case tachi_msg_BLADE_HUNTING: return "hunting";
    case tachi_msg_BLADE_WORN: return "worn";
  }
  return std::nullopt;
}

/// The blade a heartbeat figure names (tachi-sim's metric "blade"); nothing for a value that is none.
[[nodiscard]] inline std::optional<std::string_view> blade_name(double metric_value) {
  constexpr double kFirst = static_cast<int>(tachi_msg_BLADE_RAZOR), kLast = static_cast<int>(tachi_msg_BLADE_WORN);
  if (!(metric_value >= kFirst && metric_value <= kLast) ||
      metric_value != std::floor(metric_value))
    return std::nullopt;
  return blade_name(static_cast<tachi_msg_Blade>(static_cast<int>(metric_value)));
}

}  // namespace tachi::bus
