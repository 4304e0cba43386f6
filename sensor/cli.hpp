// The flags of tachi-sensor and tachi-voice: registered here, by the executables; the libraries do not need
// CLI11 for them.
#pragma once

#include "tachi/common/app.hpp"
#include "tachi/sensor/node.hpp"

namespace tachi::sensor {

struct SensorFlags {
  SensorNodeOptions options;
  bool no_dds = false;
  common::BusOptions bus;
};

struct VoiceFlags {
  VoiceNodeOptions options;
  VoiceConfig config;  ///< --config with the phrase flags applied, validated
  bool no_dds = false;
  common::BusOptions bus;
};

/// Each parses argv (and applies --log-level): an exit code when the process should stop now, else -1.
int parse_sensor_flags(int argc, char** argv, SensorFlags& flags);
int parse_voice_flags(int argc, char** argv, VoiceFlags& flags);

}  // namespace tachi::sensor
