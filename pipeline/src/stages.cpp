#include "stages.hpp"

#include "filter/cli.hpp"
#include "sensor/cli.hpp"
#include "sim/cli.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/common/app.hpp"
#include "tachi/sensor/kinect_source.hpp"
#include "tachi/sensor/voice_audio.hpp"
#include "viewer/cli.hpp"
#include "viewer/window.hpp"

#include <spdlog/spdlog.h>

#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace tachi::pipeline {
namespace {

using common::ComposedNode;

// A stage's node on its participant, with the flags it was built from (a node may keep references to
// its options, as it may in its executable's main). Members are destroyed in reverse: the node before
// the participant it writes on, the viewer's window after its node.
template <class Node, class Flags>
struct Stage {
  Flags flags;
  std::unique_ptr<viewer::ViewerWindow> window;
  std::optional<bus::Participant> dds;
  std::optional<Node> node;
};

template <class Node, class Flags>
ComposedNode composed(std::string name, bool finite, std::shared_ptr<Stage<Node, Flags>> stage) {
  return {std::move(name), finite, [stage] { return stage->node->spin_once(); }, [stage] { return stage->node->finish(); }};
}

// The stage's participant, as its executable makes it (its own identity under DDS Security).
void join_bus(std::optional<bus::Participant>& dds, const common::BusOptions& b, const std::string& identity) {
  dds.emplace(b.domain, b.dds_config, bus::Security{b.secure_dir, identity});
}

// A stage's mode without the bus (an offline run, a file view) has no place in the composed pipeline.
int runs_alone(const char* stage_and_flag, const char* why) {
  std::cerr << "tachi-pipeline: " << stage_and_flag << ' ' << why << "; run it alone\n";
  return common::kExitUsage;
}

// Each builder parses one stage's command line (argv[0] is its program's name) and appends its node.
// The `finite` each gives is the launcher's (config.cpp `plan`): what ends by itself with these flags.
using Builder = int (*)(std::span<char*> argv, Composition& out);

int build_sim(std::span<char*> argv, Composition& out) {
  auto stage = std::make_shared<Stage<sim::SimNode, sim::Flags>>();
  const auto& flags = stage->flags;
  if (const int rc = sim::parse_flags(static_cast<int>(argv.size()), argv.data(), stage->flags); rc >= 0) return rc;
  if (flags.offline) return runs_alone("tachi-sim --offline", "runs without the bus");
  join_bus(stage->dds, flags.bus, flags.bus.identity);
  stage->node.emplace(flags.options, flags.live, *stage->dds);
  out.nodes.push_back(composed("sim", flags.live.exit_when_idle_s > 0.0, stage));
  return -1;
}

int build_filter(std::span<char*> argv, Composition& out) {
  auto stage = std::make_shared<Stage<filter::FilterNode, filter::Flags>>();
  const auto& flags = stage->flags;
  if (const int rc = filter::parse_flags(static_cast<int>(argv.size()), argv.data(), stage->flags); rc >= 0) return rc;
  if (flags.offline) return runs_alone("tachi-filter --offline", "runs without the bus");
  join_bus(stage->dds, flags.bus, flags.bus.identity);
  stage->node.emplace(flags.config, flags.journal, *stage->dds);
  out.nodes.push_back(composed("filter", false, stage));
  return -1;
}

int build_sensor(std::span<char*> argv, Composition& out) {
  auto stage = std::make_shared<Stage<sensor::SensorNode, sensor::SensorFlags>>();
  const auto& flags = stage->flags;
  if (const int rc = sensor::parse_sensor_flags(static_cast<int>(argv.size()), argv.data(), stage->flags); rc >= 0) return rc;
  if (!flags.no_dds) join_bus(stage->dds, flags.bus, flags.bus.identity);
  try {
    stage->node.emplace(flags.options, stage->dds ? &*stage->dds : nullptr);
  } catch (const sensor::NoKinectError& e) {
    std::cerr << "tachi-pipeline: tachi-sensor: " << e.what() << '\n';
    return common::kExitNoDevice;
  }
  const auto& o = flags.options;
  out.nodes.push_back(composed("sensor", (!o.recording.empty() && !o.loop) || o.max_frames > 0, stage));
  return -1;
}

int build_voice(std::span<char*> argv, Composition& out) {
  auto stage = std::make_shared<Stage<sensor::VoiceNode, sensor::VoiceFlags>>();
  const auto& flags = stage->flags;
  if (const int rc = sensor::parse_voice_flags(static_cast<int>(argv.size()), argv.data(), stage->flags); rc >= 0) return rc;
  if (!flags.no_dds) join_bus(stage->dds, flags.bus, flags.bus.identity);
  try {
    stage->node.emplace(flags.options, flags.config, stage->dds ? &*stage->dds : nullptr);
  } catch (const sensor::AudioDeviceNotFound& e) {
    std::cerr << "tachi-pipeline: tachi-voice: " << e.what() << '\n';
    return common::kExitNoDevice;
  }
  out.nodes.push_back(composed("voice", !flags.options.wav.empty() || !flags.options.raw.empty(), stage));
  return -1;
}

int build_viewer(std::span<char*> argv, Composition& out) {
  auto stage = std::make_shared<Stage<viewer::ViewerNode, viewer::ViewerOptions>>();
  const auto& options = stage->flags;
  if (const int rc = viewer::parse_flags(static_cast<int>(argv.size()), argv.data(), stage->flags); rc >= 0) return rc;
  if (!options.mesh.empty()) return runs_alone("tachi-viewer --mesh", "shows a file, not the bus");
  stage->window = viewer::open_window(options);  // none with --headless
  join_bus(stage->dds, options.bus, viewer::participant_identity(options));
  stage->node.emplace(options, *stage->dds, stage->window.get());
  // The viewer's outputs name a full disk as its executable does (viewer/main.cpp).
  ComposedNode node = composed("viewer", options.exit_when_idle_s > 0.0 || stage->window != nullptr, stage);
  node.needs_calling_thread = stage->window != nullptr;  // opened on this thread; Qt's highgui is driven from it only
  node.spin_once = [stage] {
    try {
      return stage->node->spin_once();
    } catch (const std::exception&) {
      viewer::rethrow_naming_a_full_disk(stage->flags);
    }
  };
  node.finish = [stage] {
    try {
      return stage->node->finish();
    } catch (const std::exception&) {
      viewer::rethrow_naming_a_full_disk(stage->flags);
    }
  };
  out.nodes.push_back(std::move(node));
  return -1;
}

const std::map<std::string, Builder> kBuilders{{"tachi-sim", build_sim},
                                               {"tachi-filter", build_filter},
                                               {"tachi-sensor", build_sensor},
                                               {"tachi-voice", build_voice},
                                               {"tachi-viewer", build_viewer}};

}  // namespace

int compose(int argc, char** argv, Composition& composition) {
  const std::span<char*> all(argv, static_cast<std::size_t>(argc));
  std::size_t first_stage = 1;
  while (first_stage < all.size() && std::string(all[first_stage]) != "--") ++first_stage;

  CLI::App app{"tachi-pipeline: the pipeline's stages composed in one process, each on its own thread and "
               "participant (tachi run --in-process). Usage: tachi-pipeline [--log-level L] -- tachi-sim ARGS... "
               "-- tachi-filter ARGS... (tachi-sim, tachi-viewer, tachi-filter, tachi-voice, tachi-sensor; "
               "each with its own executable's flags, in start order: consumers first)"};
  app.name("tachi-pipeline");
  std::string log_level;
  common::add_log_level_flag(app, log_level);
  if (const int rc = common::parse(app, static_cast<int>(first_stage), argv); rc >= 0) return rc;
  if (first_stage + 1 >= all.size()) {
    std::cerr << "tachi-pipeline: no stage given (-- tachi-sim ARGS... -- tachi-filter ARGS...)\n";
    return common::kExitUsage;
  }

  // `tachi run`'s preflight (TACHI_CHECK_FLAGS): every stage's flags are checked, no node is built.
  const char* check = std::getenv(common::kCheckFlagsEnv);
  const bool checking_flags = check != nullptr && *check != '\0';
  bool has_sim = false;
  for (std::size_t begin = first_stage + 1; begin < all.size();) {
    std::size_t end = begin;
    while (end < all.size() && std::string(all[end]) != "--") ++end;
    const std::string program = all[begin];
    const auto builder = kBuilders.find(program);
    if (builder == kBuilders.end()) {
      std::cerr << "tachi-pipeline: " << program << ": not a stage (tachi-sim, tachi-viewer, tachi-filter, tachi-voice, tachi-sensor)\n";
      return common::kExitUsage;
    }
    const int rc = builder->second(all.subspan(begin, end - begin), composition);
    if (rc > 0 || (rc == 0 && !checking_flags)) return rc;
    has_sim = has_sim || program == "tachi-sim";
    begin = end + 1;
  }
  if (checking_flags) return common::kExitOk;
  // Every stage's parse named the default logger after itself; the composition's lines say which node.
  common::log_node_names("tachi-pipeline");
  if (app.count("--log-level") > 0) common::set_log_level(log_level);  // else each stage's --log-level, the last one parsed
  composition.grace = has_sim ? std::chrono::milliseconds(0) : std::chrono::milliseconds(500);
  return -1;
}

}  // namespace tachi::pipeline
