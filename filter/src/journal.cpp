#include "tachi/filter/journal.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>

namespace tachi::filter {
namespace {
constexpr std::size_t kStampsPerSensor = 256;  // > the 64 samples tachi/hand/raw keeps for late joiners
constexpr std::size_t kMaxSensors = 64;        // as bus::InputGuard
}  // namespace

std::string filter_journal_fingerprint(const FilterConfig& config) {
  // FNV-1a (64 bit) of the effective config: stable across builds, unlike std::hash.
  std::uint64_t h = 14695981039346656037ULL;
  for (const unsigned char c : to_json(config)) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char text[24];
  std::snprintf(text, sizeof text, "%016" PRIx64, h);
  return text;
}

std::string format_record(const FilterJournalRecord& r) {
  char line[320];
  if (r.kind == FilterJournalRecord::Kind::Voice) {
    std::snprintf(line, sizeof line, "v %d", static_cast<int>(r.voice));
    return line;
  }
  const HandSample& h = r.hand;
  // %a: hex floats, so the replayed sample is the processed one to the last bit.
  std::snprintf(line, sizeof line, "h %" PRIu32 " %" PRIu64 " %" PRId64 " %d %a %a %a %a %a %d", r.sensor_id, h.frame,
                h.stamp_ns, h.tracked ? 1 : 0, static_cast<double>(h.position_m.x()), static_cast<double>(h.position_m.y()),
                static_cast<double>(h.position_m.z()), static_cast<double>(h.confidence),
                static_cast<double>(r.proximity.distance_m), r.proximity.outside ? 1 : 0);
  return line;
}

std::optional<FilterJournalRecord> parse_filter_record(const std::string& line) {
  FilterJournalRecord r;
  int used = 0;
  if (line.starts_with("v ")) {
    int kind = -1;
    if (std::sscanf(line.c_str(), "v %d%n", &kind, &used) != 1 || static_cast<std::size_t>(used) != line.size() || kind < 0 ||
        kind > static_cast<int>(VoiceCommandKind::Release))
      return std::nullopt;
    r.kind = FilterJournalRecord::Kind::Voice;
    r.voice = static_cast<VoiceCommandKind>(kind);
    return r;
  }
  double x = 0, y = 0, z = 0, confidence = 0, distance = 0;
  int tracked = 0, outside = 0;
  HandSample& h = r.hand;
  if (std::sscanf(line.c_str(), "h %" SCNu32 " %" SCNu64 " %" SCNd64 " %d %la %la %la %la %la %d%n", &r.sensor_id, &h.frame,
                  &h.stamp_ns, &tracked, &x, &y, &z, &confidence, &distance, &outside, &used) != 10 ||
      static_cast<std::size_t>(used) != line.size() || (tracked != 0 && tracked != 1) || (outside != 0 && outside != 1))
    return std::nullopt;
  h.tracked = tracked == 1;
  h.position_m = Eigen::Vector3d{x, y, z}.cast<float>();
  h.confidence = static_cast<float>(confidence);
  r.proximity.distance_m = static_cast<float>(distance);
  r.proximity.outside = outside == 1;
  return r;
}

FilterJournal::FilterJournal(std::filesystem::path path, const FilterConfig& config, std::uint64_t new_session_id,
                             std::uintmax_t max_bytes)
    : file_(std::move(path), "tachi-filter-journal 1 " + filter_journal_fingerprint(config),
            [this](const std::string& line) {
              if (!recovered_session_) {
                // The line after the header names the session; nothing else may come first.
                std::uint64_t session = 0;
                int used = 0;
                if (std::sscanf(line.c_str(), "s %" SCNu64 "%n", &session, &used) != 1 ||
                    static_cast<std::size_t>(used) != line.size())
                  return false;
                recovered_session_ = session;
                return true;
              }
              const auto r = parse_filter_record(line);
              if (r) recovered_.push_back(*r);
              return r.has_value();
            },
            max_bytes) {
  if (recovered_session_) {
    session_id_ = *recovered_session_;
    return;
  }
  // A new journal (or one killed before its session line was whole): this run's session starts it.
  session_id_ = new_session_id;
  file_.append("s " + std::to_string(session_id_));
  file_.flush();
}

bool ProcessedSamples::contains(std::uint32_t sensor_id, std::int64_t stamp_ns) const {
  const auto it = stamps_.find(sensor_id);
  if (it == stamps_.end() || it->second.empty()) return false;
  // The usual case, a new sample newer than every one processed, is answered without a search.
  if (stamp_ns > it->second.back()) return false;
  return std::find(it->second.rbegin(), it->second.rend(), stamp_ns) != it->second.rend();
}

void ProcessedSamples::add(std::uint32_t sensor_id, std::int64_t stamp_ns) {
  auto it = stamps_.find(sensor_id);
  if (it == stamps_.end()) {
    if (stamps_.size() >= kMaxSensors) return;  // a flood of made-up sensors: the guard counts those
    it = stamps_.emplace(sensor_id, std::deque<std::int64_t>{}).first;
  }
  it->second.push_back(stamp_ns);
  if (it->second.size() > kStampsPerSensor) it->second.pop_front();
}

FilterReplay replay(const std::vector<FilterJournalRecord>& records, StrokeFilter& filter) {
  FilterReplay out;
  for (const FilterJournalRecord& r : records) {
    if (r.kind == FilterJournalRecord::Kind::Voice) {
      (void)filter.on_voice(r.voice);  // a refused grab was logged the first time
      continue;
    }
    out.last.emplace(r.sensor_id, filter.on_hand(r.hand, r.proximity));
    out.processed.add(r.sensor_id, r.hand.stamp_ns);
  }
  return out;
}

}  // namespace tachi::filter
