// No lost cuts (docs/reliability.md): the live simulator's journal. Every hand sample the
// Session applied is appended with the step it was applied at, flushed with each batch, so a
// simulator killed mid-run and started again with the same journal replays the same samples at the
// same steps into a new Session, which (the solver and the cutter being deterministic) reaches the
// same cloth: the same topology, the same cut lines, the same pieces. Then it resumes live.
//
// Format: text, one record a line, append-only.
//   tachi-sim-journal 1 <fingerprint>          first line: the run's configuration (grid, pinning,
//                                              size, blade, solver); a journal of another config is refused
//   h <step> <sensor> <session> <time_ns> <stroke> <x> <y> <z> <flags>   a hand sample (flags: tracked 1,
//                                              cutting 2, holding 4, grabbing 8), position as C99 hex floats (exact)
//   e <step>                                   the open stroke was ended (its publisher went away)
// A torn last line (a kill mid-write) is dropped on reading; any other bad line is an error naming it.
#pragma once

#include "tachi/common/line_journal.hpp"
#include "tachi/sim/session.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace tachi::sim {

/// One journal record: a hand sample (with where it came from) or an end of stroke.
struct JournalRecord {
  enum class Kind : char { Hand = 'h', EndStroke = 'e' };
  Kind kind = Kind::Hand;
  std::uint64_t step = 0;       ///< Session::steps() when it was applied
  std::uint32_t sensor_id = 0;  ///< with session_id and time_ns: which published sample this was
  std::int64_t time_ns = 0;
  HandInput hand;
};

/// The configuration a journal belongs to, as one line: a journal replays only into the same cloth.
std::string journal_fingerprint(const SessionOptions& options);

/// Formats and parses one record line (without the newline); parse returns nothing for a bad line.
std::string format_record(const JournalRecord& record);
std::optional<JournalRecord> parse_record(const std::string& line);

/// A journal file being replayed and appended to.
class Journal {
 public:
  /// Bounds the file: a run that outgrows it stops journaling (logged once) instead of filling the disk.
  static constexpr std::uintmax_t kMaxBytes = std::uintmax_t{256} << 20;

  /// Opens (creating) `path` for `fingerprint`. Reads the records already there; throws
  /// std::runtime_error naming the file and line when it belongs to another configuration or a
  /// record other than the last is corrupt.
  Journal(std::filesystem::path path, const std::string& fingerprint, std::uintmax_t max_bytes = kMaxBytes);

  /// The records found on opening, in order.
  [[nodiscard]] const std::vector<JournalRecord>& recovered() const { return recovered_; }
  /// Appends a record (buffered until flush()). Returns false once the journal is full.
  bool append(const JournalRecord& record);
  /// Writes the buffered records through to the file (one write + fflush; no fsync: the journal
  /// survives the process, not the machine).
  void flush() { file_.flush(); }
  [[nodiscard]] bool full() const { return file_.full(); }
  [[nodiscard]] const std::filesystem::path& path() const { return file_.path(); }

 private:
  std::vector<JournalRecord> recovered_;  // before file_: filled while file_ is constructed
  common::LineJournal file_;
};

/// Replays `records` into a fresh `session`: steps it to each record's step, then applies the record.
/// Returns, per (sensor, filter session), the newest sample time applied, so the live loop can tell a
/// sample it already applied (re-delivered by the filter's transient-local history) from a new one.
std::map<std::pair<std::uint32_t, std::uint64_t>, std::int64_t> replay(const std::vector<JournalRecord>& records,
                                                                        Session& session);

}  // namespace tachi::sim
