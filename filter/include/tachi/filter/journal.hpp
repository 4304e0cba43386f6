// No lost cuts (docs/reliability.md): the filter's journal. A tachi-filter killed mid-stroke
// and started again with the same journal replays what it had been given (every hand sample with the
// hand-to-cloth proximity it measured then, every voice command) into a fresh StrokeFilter, which (the
// smoother and the gate being deterministic) reaches the killed filter's state: the same smoothed hand,
// the same open stroke, the same stroke numbers, under the same session id. It then takes the hand
// samples published while it was down from the sensor's history (tachi/hand/raw is transient-local),
// skipping those the journal holds, and the stroke goes on without a gap and without a second id.
//
// Format: text, one record a line, append-only (common::LineJournal: header, torn last line dropped).
//   tachi-filter-journal 1 <fingerprint>       first line: the filter's configuration
//   s <session_id>                             second line: the session every restart carries on
//   h <sensor> <frame> <stamp_ns> <tracked> <x> <y> <z> <confidence> <distance_m> <outside>
//                                              a hand sample (camera frame; C99 hex floats, exact) and
//                                              the proximity to the cloth measured for it
//   v <command>                                a voice command (0 start, 1 stop, 2 grab, 3 release)
#pragma once

#include "tachi/common/line_journal.hpp"
#include "tachi/filter/cloth_proximity.hpp"
#include "tachi/filter/config.hpp"
#include "tachi/filter/stroke_filter.hpp"
#include "tachi/filter/types.hpp"

#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tachi::filter {

struct FilterJournalRecord {
  enum class Kind : char { Hand = 'h', Voice = 'v' };
  Kind kind = Kind::Hand;
  std::uint32_t sensor_id = 0;
  HandSample hand;
  Proximity proximity;  ///< as measured when the sample was first processed (only distance and outside)
  VoiceCommandKind voice = VoiceCommandKind::Start;
};

/// The configuration a journal belongs to: a hash of the effective config's JSON.
std::string filter_journal_fingerprint(const FilterConfig& config);

/// Formats and parses one record line (without the newline); parse returns nothing for a bad line.
std::string format_record(const FilterJournalRecord& record);
std::optional<FilterJournalRecord> parse_filter_record(const std::string& line);

class FilterJournal {
 public:
  static constexpr std::uintmax_t kMaxBytes = std::uintmax_t{64} << 20;  // ~7 h of hand at 30 Hz

  /// Opens (creating) `path` for `config`. A new journal takes `new_session_id`; an existing one keeps
  /// the session it was started with. Throws std::runtime_error naming the file (and line) when it
  /// belongs to another configuration or is corrupt.
  FilterJournal(std::filesystem::path path, const FilterConfig& config, std::uint64_t new_session_id,
                std::uintmax_t max_bytes = kMaxBytes);

  [[nodiscard]] std::uint64_t session_id() const { return session_id_; }
  [[nodiscard]] const std::vector<FilterJournalRecord>& recovered() const { return recovered_; }
  /// Appends a record (buffered until flush()). Returns false once the journal is full.
  bool append(const FilterJournalRecord& record) { return file_.append(format_record(record)); }
  void flush() { file_.flush(); }
  [[nodiscard]] bool full() const { return file_.full(); }
  [[nodiscard]] const std::filesystem::path& path() const { return file_.path(); }

 private:
  std::vector<FilterJournalRecord> recovered_;  // before file_: filled while file_ is constructed
  std::optional<std::uint64_t> recovered_session_;
  common::LineJournal file_;
  std::uint64_t session_id_ = 0;
};

/// The hand samples a filter has processed, by (sensor, capture time): the last 256 per sensor, for at
/// most 64 sensors. A sample seen again (re-delivered from the sensor's history to a restarted filter,
/// or a frame a restarted sensor sends twice) is skipped, not processed twice.
class ProcessedSamples {
 public:
  [[nodiscard]] bool contains(std::uint32_t sensor_id, std::int64_t stamp_ns) const;
  void add(std::uint32_t sensor_id, std::int64_t stamp_ns);

 private:
  std::map<std::uint32_t, std::deque<std::int64_t>> stamps_;
};

struct FilterReplay {
  ProcessedSamples processed;  ///< the hand samples replayed
  std::optional<std::pair<std::uint32_t, StrokeSample>> last;  ///< the last hand sample's output, with its sensor
};

/// Replays `records` into a fresh `filter` (nothing is published).
FilterReplay replay(const std::vector<FilterJournalRecord>& records, StrokeFilter& filter);

}  // namespace tachi::filter
