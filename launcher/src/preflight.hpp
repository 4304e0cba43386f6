// What `tachi run` checks before it starts any node, so that a mistake the user made is named at
// once (the flag, the folder) instead of surfacing seconds into a run that then prints a zeroed
// headline as if it had run: --out is a folder the run can write, with room for what the run will
// write there, and every node accepts the command line the run would give it (--set, the config's
// node objects, --blade, ...), as each node's own flag parser judges it.
#pragma once

#include "tachi/launcher/config.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace tachi::launcher {

/// A preflight finding: the one line to print after "tachi run: ", and the exit code (RunExit).
struct PreflightError {
  std::string message;
  int exit_code;
};

/// Bytes a run will write into --out, from the grid, the recording's length (or a minute, live) and
/// the video. Deliberately generous: it decides whether to start at all, not how much to reserve.
[[nodiscard]] std::uint64_t estimate_output_bytes(const RunConfig& config);

/// --out: a folder (created if missing) the launcher may write, with at least `needed_bytes` free.
/// The message names --out and the path that is in the way.
[[nodiscard]] std::optional<PreflightError> check_out_folder(const RunConfig& config, std::uint64_t needed_bytes);

/// Runs each planned node with its run's command line and kCheckFlagsEnv set (the node parses its
/// flags and exits), so a flag a node refuses stops the run before any node starts. The message
/// names the user's setting that carries the refused flag (`--set sim.materal=denim`) and the node's
/// own one-line reason.
[[nodiscard]] std::optional<PreflightError> check_node_flags(const RunConfig& config, const std::filesystem::path& bin_dir);

}  // namespace tachi::launcher
