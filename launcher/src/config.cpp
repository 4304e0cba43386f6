#include "tachi/launcher/config.hpp"

#include "tachi/common/json_value.hpp"

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

namespace tachi::launcher {
namespace {

using nlohmann::json;

const std::set<std::string> kTopKeys{"recording", "live",   "rate",       "gate",     "voice_wav", "voice_device",
                                     "blade",     "grid",   "domain",     "dds_config", "out",     "headless",
                                     "settle_s",  "nodes",  "secure", "mouse", "video", "lossy", "in_process"};

std::invalid_argument bad(const std::string& key, const std::string& why) {
  return std::invalid_argument("config key \"" + key + "\": " + why);
}

template <class T>
T get(const json& config, const std::string& key, const T& fallback) {
  const auto it = config.find(key);
  if (it == config.end() || it->is_null()) return fallback;
  try {
    return common::json_value<T>(*it);
  } catch (const json::exception&) {
    throw bad(key, "has the wrong type (" + std::string(it->type_name()) + ")");
  } catch (const std::invalid_argument& e) {
    throw bad(key, e.what());
  }
}

std::vector<std::string> split_nodes(const json& value) {
  std::vector<std::string> nodes;
  if (value.is_string()) {
    std::stringstream in(value.get<std::string>());
    for (std::string node; std::getline(in, node, ',');)
      if (!node.empty()) nodes.push_back(node);
  } else if (value.is_array()) {
    for (const auto& n : value) {
      if (!n.is_string()) throw bad("nodes", "must hold node names");
      nodes.push_back(n.get<std::string>());
    }
  } else {
    throw bad("nodes", "must be a list like \"sensor,filter\"");
  }
  return nodes;
}

std::string value_text(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  return v.dump();  // numbers keep JSON's shortest round-trip form
}

}  // namespace

bool RunConfig::has(const std::string& node) const { return std::find(nodes.begin(), nodes.end(), node) != nodes.end(); }

json default_config_json(bool have_display) {
  json node_options = json::object();
  // The cloth hangs from its top edge, like a curtain the user cuts (the bundled recordings assume it),
  // 1 m above a floor (the 1 m cloth is centred at the origin) where the pieces cut off come to rest: without
  // one they fell for ever, at 19.6 m/s after two seconds, out of every reader's range.
  node_options["sim"] = {{"pin", "top-edge"}, {"ground", kFloorHeightM}};
  for (const auto& n : kNodes)
    if (!node_options.contains(n)) node_options[n] = json::object();
  json config = to_json(RunConfig{});
  config["headless"] = !have_display;
  config["nodes"] = "sensor,filter,sim,viewer";
  merge_into(config, node_options);
  return config;
}

RunConfig from_json(const json& config) {
  if (!config.is_object()) throw std::invalid_argument("config: expected a JSON object");
  RunConfig c;
  for (const auto& [key, value] : config.items()) {
    const bool node = std::find(kNodes.begin(), kNodes.end(), key) != kNodes.end();
    if (node) {
      if (!value.is_object()) throw bad(key, "node options must be an object of flag: value");
      continue;
    }
    if (!kTopKeys.contains(key)) throw bad(key, "unknown (allowed: the run options or a node name: sensor, filter, sim, viewer, voice)");
  }
  c.recording = get<std::string>(config, "recording", "");
  const bool live = get<bool>(config, "live", false);
  if (live && !c.recording.empty()) throw bad("live", "a run plays a recording or the live Kinect, not both");
  c.rate = get<std::string>(config, "rate", c.rate);
  c.gate = get<std::string>(config, "gate", c.gate);
  if (c.gate != "threshold" && c.gate != "voice" && c.gate != "either") throw bad("gate", "must be threshold, voice or either");
  c.voice_wav = get<std::string>(config, "voice_wav", "");
  c.voice_device = get<std::string>(config, "voice_device", "");
  if (!c.voice_wav.empty() && !c.voice_device.empty()) throw bad("voice_wav", "give one voice source (voice_wav or voice_device)");
  c.blade = get<std::string>(config, "blade", "");
  c.grid = get<int>(config, "grid", c.grid);
  if (c.grid < 2 || c.grid > 1024) throw bad("grid", "must be in [2, 1024]");
  const auto domain = get<long long>(config, "domain", 0);
  if (domain < 0 || domain > 232) throw bad("domain", "must be in [0, 232]");
  c.domain = static_cast<unsigned>(domain);
  c.dds_config = get<std::string>(config, "dds_config", "");
  c.secure = get<std::string>(config, "secure", "");
  c.lossy_permille = get<int>(config, "lossy", 0);
  if (c.lossy_permille < 0 || c.lossy_permille > kMaxLossyPermille)
    throw bad("lossy", "must be 0-" + std::to_string(kMaxLossyPermille) + " (per mille of packets dropped)");
  c.out = get<std::string>(config, "out", c.out);
  if (c.out.empty()) throw bad("out", "must name a folder");
  c.headless = get<bool>(config, "headless", c.headless);
  c.in_process = get<bool>(config, "in_process", false);
  c.mouse = get<bool>(config, "mouse", false);
  if (c.mouse && (!c.recording.empty() || live)) throw bad("mouse", "the mouse blade replaces the camera: no recording or live");
  if (c.mouse && c.headless) throw bad("mouse", "the mouse blade needs the viewer's window (a DISPLAY, not headless)");
  c.video = get<std::string>(config, "video", c.video);
  if (!c.video.empty() && !c.video.ends_with(".mp4") && !c.video.ends_with(".avi"))
    throw bad("video", "must be a .mp4 or .avi file name (or empty: no video)");
  c.settle_s = get<double>(config, "settle_s", c.settle_s);
  if (!(c.settle_s > 0.0 && c.settle_s <= 60.0)) throw bad("settle_s", "must be in (0, 60] seconds");

  // The mouse blade writes strokes itself: no camera, no filter.
  c.nodes = split_nodes(config.contains("nodes") && !(c.mouse && config.at("nodes") == json("sensor,filter,sim,viewer"))
                            ? config.at("nodes")
                            : json(c.mouse ? "sim,viewer" : "sensor,filter,sim,viewer"));
  if (c.nodes.empty()) throw bad("nodes", "names no node");
  for (const auto& n : c.nodes)
    if (std::find(kNodes.begin(), kNodes.end(), n) == kNodes.end())
      throw bad("nodes", "unknown node \"" + n + "\" (allowed: sensor, filter, sim, viewer, voice)");
  // A voice source implies the voice node, where this launcher runs the filter it talks to.
  const bool voice_source = !c.voice_wav.empty() || !c.voice_device.empty();
  if (voice_source && c.has("filter") && !c.has("voice")) c.nodes.push_back("voice");
  if (c.has("voice") && !voice_source) throw bad("nodes", "the voice node needs voice_wav or voice_device");
  if (c.gate != "threshold" && !voice_source && c.has("filter"))
    throw bad("gate", "gate " + c.gate + " listens for voice commands: give voice_wav or voice_device");

  for (const auto& n : kNodes) {
    c.node_options[n] = json::object();
    if (const auto it = config.find(n); it != config.end())
      for (const auto& [flag, value] : it->items()) {
        if (flag.empty() || flag.front() == '-') throw bad(n + "." + flag, "write the flag's name without dashes");
        c.node_options[n][flag] = value;
      }
  }
  return c;
}

json to_json(const RunConfig& c) {
  std::string nodes;
  for (const auto& n : c.nodes) nodes += (nodes.empty() ? "" : ",") + n;
  json j = {{"recording", c.recording}, {"rate", c.rate},       {"gate", c.gate},
            {"voice_wav", c.voice_wav}, {"voice_device", c.voice_device}, {"blade", c.blade}, {"grid", c.grid},
            {"domain", c.domain},       {"dds_config", c.dds_config}, {"secure", c.secure},   {"out", c.out},
            {"headless", c.headless},
            {"settle_s", c.settle_s},   {"nodes", nodes},             {"mouse", c.mouse},     {"video", c.video},
            {"lossy", c.lossy_permille}, {"in_process", c.in_process}};
  for (const auto& [node, options] : c.node_options.items()) j[node] = options;
  return j;
}

void merge_into(json& base, const json& overrides) {
  for (const auto& [key, value] : overrides.items()) {
    if (value.is_object() && base.contains(key) && base[key].is_object()) {
      merge_into(base[key], value);
    } else {
      base[key] = value;
    }
  }
}

json parse_set(const std::string& assignment) {
  const auto dot = assignment.find('.');
  const auto eq = assignment.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot > eq || dot == 0 || eq == dot + 1)
    throw std::invalid_argument("--set " + assignment + ": expected NODE.FLAG=VALUE, e.g. sim.material=denim");
  const std::string node = assignment.substr(0, dot);
  const std::string flag = assignment.substr(dot + 1, eq - dot - 1);
  const std::string text = assignment.substr(eq + 1);
  json value = text;
  if (text == "true" || text == "false") {
    value = text == "true";
  } else if (text == "null") {
    value = nullptr;  // takes a default flag away (sim.ground=null: no floor)
  } else {
    // A number stays a number so that --print-config shows what the node will parse.
    const json parsed = json::parse(text, nullptr, false);
    if (parsed.is_number()) value = parsed;
  }
  return json{{node, {{flag, value}}}};
}

std::vector<std::string> pass_through_args(const json& options) {
  std::vector<std::string> args;
  for (const auto& [flag, value] : options.items()) {
    const std::string name = "--" + flag;
    if (value.is_null() || (value.is_boolean() && !value.get<bool>())) continue;
    if (value.is_boolean()) {
      args.push_back(name);
    } else if (value.is_array()) {
      for (const auto& v : value) {  // a repeatable flag, or one flag with several values (--sphere X Y Z R)
        args.push_back(name);
        if (v.is_array()) {
          for (const auto& part : v) args.push_back(value_text(part));
        } else {
          args.push_back(value_text(v));
        }
      }
    } else {
      args.push_back(name);
      args.push_back(value_text(value));
    }
  }
  return args;
}

std::vector<ChildSpec> plan(const RunConfig& c) {
  const std::filesystem::path out(c.out);
  std::vector<std::string> bus{"--domain", std::to_string(c.domain)};
  if (!c.dds_config.empty()) {
    bus.push_back("--dds-config");
    bus.push_back(c.dds_config);
  }
  if (!c.secure.empty()) {  // each node uses its own identity (its name) from the folder
    bus.push_back("--secure");
    bus.push_back(c.secure);
    // In one process Cyclone grants every participant of a domain the first one's permissions: the
    // composed nodes share one identity, whose grant is their union (the process is the security
    // boundary, as a ROS 2 enclave is).
    if (c.in_process) bus.insert(bus.end(), {"--identity", kInProcessIdentity});
  }
  const bool recording = !c.recording.empty();
  std::vector<ChildSpec> children;
  for (const auto& node : kNodes) {
    if (!c.has(node)) continue;
    ChildSpec child{node, "tachi-" + node, bus, false};
    auto& a = child.args;
    if (node == "sim") {
      a.insert(a.end(), {"--grid", std::to_string(c.grid), "--export", (out / kSimExportDir).string()});
      // No lost cuts (docs/reliability.md): a simulator the launcher restarts replays this run's journal.
      a.insert(a.end(), {"--journal", (out / "sim.journal").string()});
      if (!c.blade.empty()) a.insert(a.end(), {"--blade", c.blade});
      // An object taken from the recording lands where the hand does: the simulator maps the scene with the
      // workspace of the filter's config (unless sim.workspace-config names another).
      const json filter_options = c.node_options.value("filter", json::object());
      if (filter_options.contains("config") && filter_options.at("config").is_string() &&
          !c.node_options.value("sim", json::object()).contains("workspace-config"))
        a.insert(a.end(), {"--workspace-config", filter_options.at("config").get<std::string>()});
      // With a recording, the cloth has settled this long after the last hand sample: the run's end.
      if (recording) a.insert(a.end(), {"--exit-when-idle", json(c.settle_s).dump()});
      child.finite = recording;
    } else if (node == "viewer") {
      if (c.headless) a.push_back("--headless");
      // The `p` key's snapshots join the run's other outputs, not the folder tachi was started in.
      a.insert(a.end(), {"--snapshot", (out / "final.png").string(), "--snapshot-dir", out.string()});
      if (!c.video.empty()) a.insert(a.end(), {"--video", (out / c.video).string()});
      if (c.mouse) a.push_back("--mouse");
      // The simulator publishes states until it ends: a second without one means it has.
      if (recording) a.insert(a.end(), {"--exit-when-idle", "1"});
      // A window the user closes (q, Esc) ends the run rather than being reopened.
      child.finite = recording || !c.headless;
    } else if (node == "filter") {
      a.insert(a.end(), {"--gate", c.gate});
      // A filter the launcher restarts replays this journal and carries the open stroke on.
      a.insert(a.end(), {"--journal", (out / "filter.journal").string()});
    } else if (node == "voice") {
      if (!c.voice_wav.empty()) {
        a.insert(a.end(), {"--wav", c.voice_wav, "--wait-readers", "5"});
        child.finite = true;
      } else {
        a.insert(a.end(), {"--device", c.voice_device});
      }
    } else if (node == "sensor") {
      if (recording) {
        // A sensor the launcher restarts goes on after the last frame it published, not from the top.
        a.insert(a.end(), {"--recording", c.recording, "--rate", c.rate, "--resume", (out / "sensor.progress").string()});
      } else {
        a.push_back("--live");
      }
      // Wait for the filter (here or on another host) so the recording's first frames are not lost.
      a.insert(a.end(), {"--wait-readers", "1"});
      child.finite = recording;
    }
    const auto extra = pass_through_args(c.node_options.value(node, json::object()));
    a.insert(a.end(), extra.begin(), extra.end());
    children.push_back(std::move(child));
  }
  return children;
}

ChildSpec composed(const std::vector<ChildSpec>& nodes) {
  ChildSpec pipeline{"pipeline", "tachi-pipeline", {}, false};
  for (const auto& node : nodes) {
    pipeline.args.push_back("--");
    pipeline.args.push_back(node.program);
    for (const auto& arg : node.args) {
      // "--" separates the stages on tachi-pipeline's command line
      if (arg == "--") throw std::invalid_argument(node.node + ": an argument \"--\" cannot pass to tachi-pipeline (in_process)");
      pipeline.args.push_back(arg);
    }
    pipeline.finite = pipeline.finite || node.finite;
  }
  return pipeline;
}

std::vector<ChildSpec> children_of(const RunConfig& config) {
  auto nodes = plan(config);
  if (!config.in_process) return nodes;
  return {composed(nodes)};
}

}  // namespace tachi::launcher
