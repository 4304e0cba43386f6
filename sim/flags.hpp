// The simulation's flags, registered by the executable on its CLI11 app (the libraries do not depend on CLI11):
// each value is checked when parsed, a bad one naming its flag and the allowed range.
#pragma once

#include "tachi/common/app.hpp"
#include "tachi/sim/object.hpp"
#include "tachi/sim/options.hpp"

namespace tachi::sim {

/// The cloth, solver, material, blade, cut mode, shapes, stroke and export flags (live and offline).
void add_offline_flags(CLI::App& app, OfflineOptions& options);

/// --object, --object-pose, --object-from-recording, --object-influence.
void add_object_flags(CLI::App& app, ObjectOptions& options);

}  // namespace tachi::sim
