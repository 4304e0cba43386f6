// An append-only journal of text lines, the file layer under the simulator's and the filter's journals
// (no lost cuts, docs/reliability.md): a header line names the configuration it belongs to,
// then one record a line. A process killed mid-write leaves at most a torn last line, which reading
// drops; any other bad line is an error naming the file and the line. Bounded: once full it stops
// appending (the caller logs it) instead of filling the disk. Flushed by the caller (one write per
// batch); no fsync: the journal outlives the process, not the machine.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace tachi::common {

class LineJournal {
 public:
  /// Accepts one record line (without its newline): false when it is not a well-formed record.
  using LineReader = std::function<bool(const std::string& line)>;

  /// Opens (creating) `path`, whose first line must be `header` ("<kind> <version> <fingerprint>").
  /// Hands each complete record line already there to `read`, in order. Throws std::runtime_error
  /// naming the file (and the line) when the header belongs to another configuration or a line other
  /// than the last is corrupt, or the file cannot be read or opened for appending.
  LineJournal(std::filesystem::path path, const std::string& header, const LineReader& read, std::uintmax_t max_bytes);

  /// Appends a line (buffered until flush()). Returns false once the journal is full.
  bool append(const std::string& line);
  /// Writes the buffered lines through to the file; throws naming the file when that fails.
  void flush();
  [[nodiscard]] bool full() const { return full_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  std::uintmax_t bytes_ = 0;
  std::uintmax_t max_bytes_;
  bool full_ = false;
};

}  // namespace tachi::common
