#include "tachi/filter/hand_csv.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace tachi::filter {

namespace {
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

template <class T>
bool parse_int(const std::string& s, T& value) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  return ec == std::errc{} && ptr == s.data() + s.size();
}

bool parse_float(const std::string& s, float& value) {
  if (s.empty()) return false;
  char* end = nullptr;
  value = std::strtof(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

bool parse_bool(const std::string& s, bool& value) {
  if (s == "1" || s == "true" || s == "True") return value = true, true;
  if (s == "0" || s == "false" || s == "False") return value = false, true;
  return false;
}
}  // namespace

HandCsv read_hand_csv(std::istream& in) {
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error("hand CSV is empty (expected a header frame,stamp_ns,x,y,z,...)");
  const auto header = split(line);
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  for (const char* required : {"frame", "stamp_ns", "x", "y", "z", "tracked"})
    if (!column.contains(required))
      throw std::runtime_error(std::string("hand CSV header lacks column \"") + required +
                               "\" (expected frame,stamp_ns,x,y,z,u,v,tracked,confidence)");
  const std::size_t need = std::max({column["frame"], column["stamp_ns"], column["x"], column["y"], column["z"],
                                     column["tracked"]}) + 1;
  const bool has_confidence = column.contains("confidence");

  HandCsv result;
  std::size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto cells = split(line);
    const auto skip = [&](const std::string& why) {
      result.skipped.push_back("line " + std::to_string(line_no) + ": " + why);
    };
    if (cells.size() < need) {
      skip("too few columns");
      continue;
    }
    HandSample s;
    float x = 0, y = 0, z = 0;
    if (!parse_int(cells[column["frame"]], s.frame) || !parse_int(cells[column["stamp_ns"]], s.stamp_ns)) {
      skip("frame and stamp_ns must be integers");
      continue;
    }
    if (!parse_bool(cells[column["tracked"]], s.tracked)) {
      skip("tracked must be 0/1 or true/false");
      continue;
    }
    const bool xyz_ok = parse_float(cells[column["x"]], x) && parse_float(cells[column["y"]], y) &&
                        parse_float(cells[column["z"]], z);
    if (s.tracked && (!xyz_ok || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))) {
      skip("a tracked sample needs finite x, y, z");
      continue;
    }
    s.position_m = xyz_ok ? Eigen::Vector3f{x, y, z} : Eigen::Vector3f::Constant(std::nanf(""));
    if (has_confidence && column["confidence"] < cells.size()) parse_float(cells[column["confidence"]], s.confidence);
    result.samples.push_back(s);
  }
  return result;
}

void write_stroke_csv_header(std::ostream& out) { out << "frame,stamp_ns,x,y,z,gate,stroke_id\n"; }

void write_stroke_csv_row(std::ostream& out, const StrokeSample& s, bool camera_frame) {
  char xyz[96];
  const Eigen::Vector3f& p = camera_frame ? s.camera_position_m : s.position_m;
  if (s.tracked)
    std::snprintf(xyz, sizeof xyz, "%.6f,%.6f,%.6f", static_cast<double>(p.x()), static_cast<double>(p.y()),
                  static_cast<double>(p.z()));
  else
    std::snprintf(xyz, sizeof xyz, "nan,nan,nan");
  out << s.frame << ',' << s.stamp_ns << ',' << xyz << ',' << static_cast<int>(s.gate) << ','
      << s.stroke_id << '\n';
}

}  // namespace tachi::filter
