#include "tachi/sim/journal.hpp"

#include <cinttypes>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace tachi::sim {

std::string journal_fingerprint(const SessionOptions& o) {
  // Everything that changes what a replayed sample does to the cloth.
  std::ostringstream f;
  f << "grid=" << o.cloth.columns << 'x' << o.cloth.rows << " size=" << std::hexfloat << o.cloth.width_m << 'x'
    << o.cloth.height_m << " mass=" << o.cloth.total_mass_kg << std::defaultfloat
    << " pin=" << static_cast<int>(o.cloth.pin) << " blade=" << to_string(o.stroke.blade)
    << " cut=" << to_string(o.stroke.mode) << " dt=" << std::hexfloat
    << o.solver.dt << std::defaultfloat << " substeps=" << o.solver.substeps << " iterations=" << o.solver.iterations
    << " hand=" << std::hexfloat << o.hand_radius_m << " solver=" << to_string(o.solver_kind)
    << " blade_force=" << o.blade_force_n.value_or(0.0F) << " material=" << o.material.mass_per_area_kg_m2 << ','
    << o.material.stretch_n_per_m << ',' << o.material.shear_n_per_m << ',' << o.material.bend_n_m << ','
    << o.material.damping_per_s << std::defaultfloat << " object=" << (o.object ? o.object->points().size() : 0U);
  return f.str();
}

std::string format_record(const JournalRecord& r) {
  char line[256];
  if (r.kind == JournalRecord::Kind::EndStroke) {
    std::snprintf(line, sizeof line, "e %" PRIu64, r.step);
    return line;
  }
  const HandInput& h = r.hand;
  const int flags = (h.tracked ? 1 : 0) | (h.cutting ? 2 : 0) | (h.holding ? 4 : 0) | (h.grabbing ? 8 : 0);
  // %a: hex floats, so a replayed position is the applied one to the last bit.
  std::snprintf(line, sizeof line, "h %" PRIu64 " %" PRIu32 " %" PRIu64 " %" PRId64 " %" PRIu32 " %a %a %a %d", r.step,
                r.sensor_id, h.session_id, r.time_ns, h.stroke_id, static_cast<double>(h.position_m.x()),
                static_cast<double>(h.position_m.y()), static_cast<double>(h.position_m.z()), flags);
  return line;
}

std::optional<JournalRecord> parse_record(const std::string& line) {
  JournalRecord r;
  if (line.size() > 2 && line[0] == 'e' && line[1] == ' ') {
    int used = 0;
    if (std::sscanf(line.c_str(), "e %" SCNu64 "%n", &r.step, &used) != 1 || static_cast<std::size_t>(used) != line.size())
      return std::nullopt;
    r.kind = JournalRecord::Kind::EndStroke;
    return r;
  }
  double x = 0, y = 0, z = 0;
  int flags = 0, used = 0;
  HandInput& h = r.hand;
  if (std::sscanf(line.c_str(), "h %" SCNu64 " %" SCNu32 " %" SCNu64 " %" SCNd64 " %" SCNu32 " %la %la %la %d%n", &r.step,
                  &r.sensor_id, &h.session_id, &r.time_ns, &h.stroke_id, &x, &y, &z, &flags, &used) != 9 ||
      static_cast<std::size_t>(used) != line.size() || flags < 0 || flags > 15)
    return std::nullopt;
  h.position_m = Eigen::Vector3d{x, y, z}.cast<float>();
  h.time_s = static_cast<double>(r.time_ns) * 1e-9;
  h.tracked = (flags & 1) != 0;
  h.cutting = (flags & 2) != 0;
  h.holding = (flags & 4) != 0;
  h.grabbing = (flags & 8) != 0;
  h.sensor_id = r.sensor_id;  // the Session tells hand sources apart by it (mouse blade vs camera hand)
  return r;
}

Journal::Journal(std::filesystem::path path, const std::string& fingerprint, std::uintmax_t max_bytes)
    : file_(std::move(path), "tachi-sim-journal 1 " + fingerprint,
            [this](const std::string& line) {
              const auto r = parse_record(line);
              if (r) recovered_.push_back(*r);
              return r.has_value();
            },
            max_bytes) {}

bool Journal::append(const JournalRecord& record) { return file_.append(format_record(record)); }

std::map<std::pair<std::uint32_t, std::uint64_t>, std::int64_t> replay(const std::vector<JournalRecord>& records,
                                                                        Session& session) {
  std::map<std::pair<std::uint32_t, std::uint64_t>, std::int64_t> newest;
  for (const JournalRecord& r : records) {
    while (session.steps() < r.step) session.step();
    if (r.kind == JournalRecord::Kind::EndStroke) {
      session.end_stroke();
      continue;
    }
    session.on_hand(r.hand);
    auto& t = newest[{r.sensor_id, r.hand.session_id}];
    t = std::max(t, r.time_ns);
  }
  return newest;
}

}  // namespace tachi::sim
