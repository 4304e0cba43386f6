// What `tachi run` starts: one JSON document (a config file, then the flags on top of it) turned
// into the child processes' command lines. Node options pass through generically: each key of a
// node's object becomes `--key value` on that node's command line (true: `--key`; false/null: left
// out; an array: the flag once per element), so a flag added to a node later is reachable from the
// launcher without a change here (docs/cli.md "tachi run").
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace tachi::launcher {

/// The nodes a run may start, in start order (consumers before producers, so none misses a sample).
inline const std::vector<std::string> kNodes{"sim", "viewer", "filter", "voice", "sensor"};

/// The floor `tachi run` puts under the cloth by default (`sim.ground`, tachi-sim --ground): metres, world y.
inline constexpr double kFloorHeightM = -1.5;

/// `lossy`'s bound, bus::kMaxTransmitLossPermille (this library does not link the bus; run.cpp checks
/// that the two agree).
inline constexpr int kMaxLossyPermille = 999;

struct RunConfig {
  std::string recording;          ///< fakenect recording folder; empty = live Kinect
  std::string rate = "1";         ///< recording pace (tachi-sensor --rate)
  std::string gate = "threshold"; ///< threshold | voice | either
  std::string voice_wav;          ///< voice source: a WAV file ...
  std::string voice_device;       ///< ... or an ALSA capture device
  std::string blade;              ///< tachi-sim --blade (empty: the simulator's default)
  int grid = 64;
  unsigned domain = 0;
  std::string dds_config;         ///< empty: every node's built-in loopback config
  int lossy_permille = 0;         ///< > 0: every node's config drops this many of 1000 sent packets (bus::lossy_config_xml), up to kMaxLossyPermille
  std::string secure;             ///< DDS Security folder (scripts/make_test_pki.sh) for every node; empty: none
  std::string out = "out/run";
  bool headless = true;
  bool in_process = false;        ///< one tachi-pipeline process runs the nodes (threads), not one process each
  bool mouse = false;             ///< seed 001's blade: the viewer's --mouse cuts, no camera (sensor, filter)
  std::string video = "video.mp4";///< the viewer's render of the run, in --out (.mp4 or .avi); empty: none
  double settle_s = 2.0;          ///< a recording run ends this long after the last hand sample
  std::vector<std::string> nodes; ///< subset of kNodes this launcher starts
  nlohmann::json node_options = nlohmann::json::object();  ///< {"sim": {"pin": "top-edge"}, ...}

  [[nodiscard]] bool has(const std::string& node) const;
};

/// The built-in defaults as a JSON document (what `--print-config` shows with no file and no flags).
[[nodiscard]] nlohmann::json default_config_json(bool have_display);
/// Validates and converts; throws std::invalid_argument naming the key and the allowed values.
[[nodiscard]] RunConfig from_json(const nlohmann::json& config);
[[nodiscard]] nlohmann::json to_json(const RunConfig& config);
/// Merges `overrides` into `base` key by key (objects recursively: {"sim": {"x": 1}} adds one sim key).
void merge_into(nlohmann::json& base, const nlohmann::json& overrides);
/// "sim.material=denim" -> {"sim": {"material": "denim"}}; "true"/"false"/"null"/numbers become JSON values.
[[nodiscard]] nlohmann::json parse_set(const std::string& assignment);

/// One child process: its node name, program (next to `tachi`) and arguments.
struct ChildSpec {
  std::string node;     ///< "sim"
  std::string program;  ///< "tachi-sim"
  std::vector<std::string> args;
  /// Ends by itself when its work is done (a played recording, a settled cloth): exit 0 is then
  /// success, not a death to restart. Other children run until the launcher stops them.
  bool finite = false;
  /// Starts with SIGUSR1 blocked: it prepares while the run goes and works once sent SIGUSR1 (the
  /// plotter imports matplotlib, ~1 s, during the run instead of after it).
  bool waits_for_sigusr1 = false;
};

/// With `secure` and `in_process`: the identity every composed node uses (scripts/make_test_pki.sh makes it).
inline constexpr const char* kInProcessIdentity = "pipeline";

/// Sim export folder inside the run's output folder (the launcher collects from it).
inline constexpr const char* kSimExportDir = "sim";

/// The children of a run, in start order: one process a node.
[[nodiscard]] std::vector<ChildSpec> plan(const RunConfig& config);
/// `in_process`: the one child, tachi-pipeline, running plan()'s nodes with the same arguments
/// (`-- tachi-sim ARGS... -- tachi-viewer ARGS...`); it ends by itself when one of them would.
[[nodiscard]] ChildSpec composed(const std::vector<ChildSpec>& nodes);
/// What `tachi run` starts: plan(), or with `in_process` its composition.
[[nodiscard]] std::vector<ChildSpec> children_of(const RunConfig& config);
/// `--key value` pairs for one node's pass-through options.
[[nodiscard]] std::vector<std::string> pass_through_args(const nlohmann::json& options);

}  // namespace tachi::launcher
