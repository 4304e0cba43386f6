#include "tachi/filter/config.hpp"

#include "tachi/common/json_value.hpp"
#include "tachi/common/text_file.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <initializer_list>
#include <stdexcept>

namespace tachi::filter {

namespace {
using nlohmann::json;

[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument("filter config: " + message); }

template <class T>
void read(const json& object, const char* key, const std::string& path, T& value) {
  if (!object.contains(key)) return;
  try {
    value = common::json_value<T>(object.at(key));
  } catch (const json::exception& e) {
    fail(path + key + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    fail(path + key + " " + e.what());
  }
}

// A misspelt key would otherwise be silently ignored.
void check_keys(const json& object, std::initializer_list<const char*> allowed, const std::string& path) {
  for (const auto& item : object.items()) {
    bool known = false;
    for (const char* key : allowed) known = known || item.key() == key;
    if (!known) fail("unknown key " + path + item.key());
  }
}

const json& section(const json& root, const char* key) {
  static const json empty = json::object();
  if (!root.contains(key)) return empty;
  if (!root.at(key).is_object()) fail(std::string(key) + " must be an object");
  return root.at(key);
}

// The section's reader is common's, so the simulator maps a recorded scene exactly as the filter maps the hand.
void read_workspace(const json& w, WorkspaceMapping& m) {
  try {
    m = common::workspace_from_json(w);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}
// Floats printed through double show float noise (0.05000000074505806); 6 decimals are plenty.
double tidy(float v) { return std::round(static_cast<double>(v) * 1e6) / 1e6; }
}  // namespace

FilterConfig parse_filter_config(const std::string& json_text) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {
    fail(std::string("not valid JSON: ") + e.what());
  }
  if (!root.is_object()) fail("the document must be a JSON object");
  check_keys(root, {"workspace", "smoother", "gate", "cloth", "outliers"}, "");
  check_keys(section(root, "outliers"), {"max_hand_speed_mps", "reanchor_samples"}, "outliers.");
  check_keys(section(root, "workspace"), {"rotation", "translation_m", "scale"}, "workspace.");
  check_keys(section(root, "smoother"),
             {"kind", "moving_average_window", "min_cutoff_hz", "beta", "d_cutoff_hz", "lag_compensation", "nominal_rate_hz",
              "reset_after_gap_s"},
             "smoother.");
  check_keys(section(root, "gate"), {"mode", "enter_distance_m", "exit_distance_m", "enter_dwell_samples", "exit_dwell_samples",
                                        "max_normal_speed_mps"},
             "gate.");
  check_keys(section(root, "cloth"), {"width_m", "height_m", "outside_margin_m", "behind_cloth_is_contact"}, "cloth.");
  FilterConfig c;
  read_workspace(section(root, "workspace"), c.workspace);

  const json& s = section(root, "smoother");
  if (s.contains("kind")) {
    std::string kind;
    read(s, "kind", "smoother.", kind);
    const auto k = smoother_kind_from_string(kind);
    if (!k) fail("smoother.kind must be one of none, moving-average, one-euro, wiener, wiener-bank (got \"" + kind + "\")");
    c.smoother.kind = *k;
  }
  read(s, "moving_average_window", "smoother.", c.smoother.moving_average_window);
  read(s, "min_cutoff_hz", "smoother.", c.smoother.one_euro.min_cutoff_hz);
  read(s, "beta", "smoother.", c.smoother.one_euro.beta);
  read(s, "d_cutoff_hz", "smoother.", c.smoother.one_euro.d_cutoff_hz);
  read(s, "lag_compensation", "smoother.", c.smoother.one_euro.lag_compensation);
  read(s, "nominal_rate_hz", "smoother.", c.smoother.nominal_rate_hz);
  read(s, "reset_after_gap_s", "smoother.", c.smoother.reset_after_gap_s);
  if (const auto why = validate(c.smoother)) fail("smoother." + *why);

  const json& g = section(root, "gate");
  if (g.contains("mode")) {
    std::string mode;
    read(g, "mode", "gate.", mode);
    const auto m = gate_mode_from_string(mode);
    if (!m) fail("gate.mode must be one of threshold, voice, either (got \"" + mode + "\")");
    c.gate.mode = *m;
  }
  read(g, "enter_distance_m", "gate.", c.gate.enter_distance_m);
  read(g, "exit_distance_m", "gate.", c.gate.exit_distance_m);
  read(g, "enter_dwell_samples", "gate.", c.gate.enter_dwell_samples);
  read(g, "exit_dwell_samples", "gate.", c.gate.exit_dwell_samples);
  read(g, "max_normal_speed_mps", "gate.", c.gate.max_normal_speed_mps);
  if (const auto why = validate(c.gate)) fail(*why);

  const json& cl = section(root, "cloth");
  read(cl, "width_m", "cloth.", c.cloth.width_m);
  read(cl, "height_m", "cloth.", c.cloth.height_m);
  read(cl, "outside_margin_m", "cloth.", c.cloth.outside_margin_m);
  read(cl, "behind_cloth_is_contact", "cloth.", c.cloth.behind_cloth_is_contact);
  const auto in_range = [](float v, float lo, float hi) { return std::isfinite(v) && v > lo && v <= hi; };
  if (!in_range(c.cloth.width_m, 0.0F, 100.0F) || !in_range(c.cloth.height_m, 0.0F, 100.0F))
    fail("cloth.width_m and cloth.height_m must be in (0, 100] m");
  if (!std::isfinite(c.cloth.outside_margin_m) || c.cloth.outside_margin_m < 0.0F || c.cloth.outside_margin_m > 10.0F)
    fail("cloth.outside_margin_m must be in [0, 10] m");
  const json& o = section(root, "outliers");
  read(o, "max_hand_speed_mps", "outliers.", c.outliers.max_hand_speed_mps);
  read(o, "reanchor_samples", "outliers.", c.outliers.reanchor_samples);
  if (!std::isfinite(c.outliers.max_hand_speed_mps) || c.outliers.max_hand_speed_mps < 0.0F || c.outliers.max_hand_speed_mps > 1000.0F)
    fail("outliers.max_hand_speed_mps must be in [0, 1000] m/s (0 disables)");
  if (c.outliers.reanchor_samples < 1 || c.outliers.reanchor_samples > 1000) fail("outliers.reanchor_samples must be in [1, 1000]");
  return c;
}

FilterConfig load_filter_config(const std::string& path) {
  return parse_filter_config(common::read_text_file(path, "filter config"));
}

std::string to_json(const FilterConfig& c) {
  json rotation = json::array();
  for (int r = 0; r < 3; ++r) rotation.push_back({tidy(c.workspace.rotation(r, 0)), tidy(c.workspace.rotation(r, 1)), tidy(c.workspace.rotation(r, 2))});
  const json root{
      {"workspace",
       {{"rotation", rotation},
        {"translation_m", {tidy(c.workspace.translation_m.x()), tidy(c.workspace.translation_m.y()), tidy(c.workspace.translation_m.z())}},
        {"scale", tidy(c.workspace.scale)}}},
      {"smoother",
       {{"kind", to_string(c.smoother.kind)},
        {"moving_average_window", c.smoother.moving_average_window},
        {"min_cutoff_hz", c.smoother.one_euro.min_cutoff_hz},
        {"beta", c.smoother.one_euro.beta},
        {"d_cutoff_hz", c.smoother.one_euro.d_cutoff_hz},
        {"lag_compensation", c.smoother.one_euro.lag_compensation},
        {"nominal_rate_hz", c.smoother.nominal_rate_hz},
        {"reset_after_gap_s", c.smoother.reset_after_gap_s}}},
      {"gate",
       {{"mode", to_string(c.gate.mode)},
        {"enter_distance_m", tidy(c.gate.enter_distance_m)},
        {"exit_distance_m", tidy(c.gate.exit_distance_m)},
        {"enter_dwell_samples", c.gate.enter_dwell_samples},
        {"exit_dwell_samples", c.gate.exit_dwell_samples},
        {"max_normal_speed_mps", tidy(c.gate.max_normal_speed_mps)}}},
      {"cloth",
       {{"width_m", tidy(c.cloth.width_m)},
        {"height_m", tidy(c.cloth.height_m)},
        {"outside_margin_m", tidy(c.cloth.outside_margin_m)},
        {"behind_cloth_is_contact", c.cloth.behind_cloth_is_contact}}},
      {"outliers", {{"max_hand_speed_mps", tidy(c.outliers.max_hand_speed_mps)}, {"reanchor_samples", c.outliers.reanchor_samples}}}};
  return root.dump(2);
}

}  // namespace tachi::filter
