// Helpers shared by the sensor tests: scratch folders and hand-made fakenect files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "paths.hpp"
#include "scratch_dir.hpp"
#include "tachi/sensor/depth_frame.hpp"

namespace tachi::sensor::test {

using tachi::test::ScratchDir;  // tests/support/scratch_dir.hpp

inline void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
}

/// A depth file exactly as fakenect-record writes it (header + little-endian uint16).
inline std::string fakenect_depth_bytes(const std::vector<std::uint16_t>& raw, const std::string& header = "P5 640 480 65535\n") {
  std::string bytes = header;
  for (const std::uint16_t v : raw) {
    bytes.push_back(static_cast<char>(v & 0xff));
    bytes.push_back(static_cast<char>(v >> 8));
  }
  return bytes;
}

inline std::vector<std::uint16_t> ramp_frame(std::uint16_t offset) {
  std::vector<std::uint16_t> raw(kDepthPixels);
  for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = static_cast<std::uint16_t>((i + offset) % 2048);
  return raw;
}

inline std::string recordings_dir() { return tachi::test::recordings_dir(); }

/// Every bundled scenario (a spec in recordings/scenarios, rendered at build time), sorted, so a
/// new spec is tested without being listed again here.
inline std::vector<std::string> scenario_names() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(tachi::test::source_dir() + "/recordings/scenarios"))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace tachi::sensor::test
