#include "tachi/filter/hand_csv.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "tachi/common/csv.hpp"

namespace tachi::filter {

HandCsv read_hand_csv(std::istream& in) {
  common::CsvReader csv(in);
  if (csv.header().empty()) throw std::runtime_error("hand CSV is empty (expected a header frame,stamp_ns,x,y,z,...)");
  const auto required = [&](const char* name) {
    if (const auto i = csv.column(name)) return *i;
    throw std::runtime_error(std::string("hand CSV header lacks column \"") + name +
                             "\" (expected frame,stamp_ns,x,y,z,u,v,tracked,confidence)");
  };
  const std::size_t frame = required("frame"), stamp_ns = required("stamp_ns"), x = required("x"),
                    y = required("y"), z = required("z"), tracked = required("tracked");
  const std::size_t need = std::max({frame, stamp_ns, x, y, z, tracked}) + 1;
  const std::optional<std::size_t> confidence = csv.column("confidence");

  HandCsv result;
  while (const auto row = csv.next()) {
    const auto& cells = row->cells;
    const auto skip = [&](const std::string& why) {
      result.skipped.push_back("line " + std::to_string(row->line) + ": " + why);
    };
    if (cells.size() < need) {
      skip("too few columns");
      continue;
    }
    HandSample s;
    const auto frame_no = common::to_uint64(cells[frame]);
    const auto stamp = common::to_int64(cells[stamp_ns]);
    if (!frame_no || !stamp) {
      skip("frame and stamp_ns must be integers");
      continue;
    }
    s.frame = *frame_no;
    s.stamp_ns = *stamp;
    const auto is_tracked = common::to_bool(cells[tracked]);
    if (!is_tracked) {
      skip("tracked must be 0/1 or true/false");
      continue;
    }
    s.tracked = *is_tracked;
    const auto px = common::to_float(cells[x]), py = common::to_float(cells[y]), pz = common::to_float(cells[z]);
    const bool xyz_ok = px && py && pz;
    if (s.tracked && !xyz_ok) {
      skip("a tracked sample needs finite x, y, z");
      continue;
    }
    s.position_m = xyz_ok ? Eigen::Vector3f{*px, *py, *pz} : Eigen::Vector3f::Constant(std::nanf(""));
    if (confidence && *confidence < cells.size())
      if (const auto c = common::to_float(cells[*confidence])) s.confidence = *c;
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
