// tachi-pipeline's composition: the stages named on its command line, each parsed by its own
// executable's flags (sim/cli.hpp, ...) and built as the same node class that executable runs, on a
// participant of its own (its own identity under DDS Security), ready for common::run_composed.
#pragma once

#include "tachi/common/composition.hpp"

#include <chrono>
#include <vector>

namespace tachi::pipeline {

struct Composition {
  std::vector<common::ComposedNode> nodes;  ///< in command-line order: consumers first, as `tachi run` plans them
  /// How long the non-finite nodes (the filter) pass samples on after the finite ones are done: none when
  /// the simulator, their last reader, has finished (`tachi run`'s rule for its children).
  std::chrono::milliseconds grace{0};
};

/// argv: `tachi-pipeline [--log-level L] -- PROGRAM ARGS... [-- PROGRAM ARGS...]...`, PROGRAM one of
/// tachi-sim, tachi-viewer, tachi-filter, tachi-voice, tachi-sensor with the arguments that executable
/// takes. Builds the nodes in that order (a stage constructed after its readers misses none of its first
/// samples). An exit code when the process should stop now (help, `TACHI_CHECK_FLAGS`, a bad flag: as
/// the stage's executable would answer; kExitNoDevice without a Kinect or audio device), else -1.
int compose(int argc, char** argv, Composition& composition);

}  // namespace tachi::pipeline
