// The offline driver of tachi-sim (no DDS): build a cloth, step it (cutting along a stroke file), export the final
// mesh (OBJ), pattern (SVG) and a summary (JSON). The options, the summary and the export are their own units,
// shared with the live mode (options.hpp, summary.hpp, export.hpp).
#pragma once

#include "tachi/sim/export.hpp"
#include "tachi/sim/options.hpp"
#include "tachi/sim/summary.hpp"

namespace tachi::sim {

/// Runs the offline simulation and, when export_dir is set, writes export_dir/cloth.obj and
/// export_dir/summary.json. Throws std::runtime_error on an I/O failure; options must be valid.
Summary run_offline(const OfflineOptions& options);

}  // namespace tachi::sim
