// The filter's configuration: workspace mapping, smoother, gate, cloth extent.
// Read from JSON (config/filter.json shows every key with its default) and validated when parsed.
#pragma once

#include "tachi/filter/cloth_proximity.hpp"
#include "tachi/filter/gate.hpp"
#include "tachi/filter/smoothing.hpp"
#include "tachi/filter/stroke_outliers.hpp"
#include "tachi/filter/workspace.hpp"

#include <string>

namespace tachi::filter {

struct FilterConfig {
  WorkspaceMapping workspace = default_mapping();
  SmootherParams smoother;
  GateParams gate;
  ClothProximityParams cloth;
  OutlierParams outliers;
};

/// Parses a JSON document; missing keys keep their defaults. Throws std::invalid_argument naming the
/// key and the allowed range when a value is unusable, or when the document is not valid JSON.
FilterConfig parse_filter_config(const std::string& json_text);
/// Reads and parses a file; throws std::runtime_error when it cannot be read.
FilterConfig load_filter_config(const std::string& path);
/// The configuration as JSON (every key), for `--print-config` and docs.
std::string to_json(const FilterConfig& config);

}  // namespace tachi::filter
