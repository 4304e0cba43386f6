// The randomized world's resting pose on the command line: tachi-synth --random and tachi-sensor-eval
// --random/--frames register the same two flags here, so each names itself in its errors.
#pragma once

#include <string>

#include "tachi/common/app.hpp"

namespace tachi::sensor {

/// --hanging-rest (the default since session 35) and --floating-rest (the previous world), which exclude each
/// other; `with` names the options they apply to in the help, and each needs `needs` when it is given.
inline void add_resting_flags(CLI::App& app, bool& hanging_rest, const std::string& with, CLI::Option* needs = nullptr) {
  auto* hanging = app.add_flag("--hanging-rest")->description(
      "With " + with + ": the hand rests at the arm's end, fingers down (the default since session 35; docs/sensor.md)");
  auto* floating = app.add_flag_callback(
      "--floating-rest", [&hanging_rest] { hanging_rest = false; },
      "With " + with +
          ": the previous world's resting pose, 0.72 m below the shoulder, beyond the arm's reach and drawn "
          "detached from it, physically impossible (to compare with figures taken before session 35)");
  hanging->excludes(floating);
  if (needs != nullptr) {
    hanging->needs(needs);
    floating->needs(needs);
  }
}

}  // namespace tachi::sensor
