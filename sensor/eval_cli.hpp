// tachi-sensor-eval's flags: registered here, by the executable; the evaluation is tachi_sensor's (evaluation.hpp).
#pragma once

#include "tachi/sensor/evaluation.hpp"

namespace tachi::sensor {

/// Parses argv (and applies --log-level). An exit code when the process should stop now (help: 0; a bad flag,
/// a bad --random range, CSV files with --random or a missing one: kExitUsage naming it), else -1.
int parse_eval_flags(int argc, char** argv, EvaluationOptions& options);

}  // namespace tachi::sensor
