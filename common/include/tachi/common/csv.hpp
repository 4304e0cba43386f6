// One small reader for the project's own CSV formats (hand samples, ground truth, strokes): a header
// line names the columns, each later line is a row of comma-separated cells. Callers find columns by
// header name and parse cells with the typed parsers below; what a bad row means (throw, skip and
// report, count) stays each caller's policy.
//
// Deliberately not RFC 4180: there is no quoting or escaping. A quote is an ordinary character, so
// `"a,b"` is two cells, `"a` and `b"`; our formats hold only numbers and plain names.
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tachi::common {

/// One data row: its 1-based line number in the input (for messages) and its cells.
struct CsvRow {
  std::size_t line = 0;
  std::vector<std::string> cells;
};

/// Reads the header on construction, then rows one at a time. Cells are trimmed of spaces and tabs,
/// a trailing CR (a Windows line end) is dropped, and blank (empty or whitespace-only) lines are
/// skipped, before the header too. A trailing comma yields a last, empty cell.
class CsvReader {
 public:
  explicit CsvReader(std::istream& in);

  /// The header's cells; empty when the input has no non-blank line.
  [[nodiscard]] const std::vector<std::string>& header() const { return header_; }
  /// Index of the header cell `name` (exact match; the last one when a name repeats), if there is one.
  [[nodiscard]] std::optional<std::size_t> column(std::string_view name) const;
  /// The next non-blank row, or nothing at the end of the input.
  [[nodiscard]] std::optional<CsvRow> next();

 private:
  std::istream* in_;
  std::size_t line_ = 0;
  std::vector<std::string> header_;
};

/// The cells of one line, split at every comma and trimmed (see CsvReader).
[[nodiscard]] std::vector<std::string> split_csv_line(std::string_view line);

/// Typed cell parsers: the whole cell must be the value, else nothing. The float parsers accept a
/// leading '+' and return nothing for nan, inf and out-of-range values.
[[nodiscard]] std::optional<std::int64_t> to_int64(std::string_view cell);
[[nodiscard]] std::optional<std::uint64_t> to_uint64(std::string_view cell);
[[nodiscard]] std::optional<double> to_double(std::string_view cell);
[[nodiscard]] std::optional<float> to_float(std::string_view cell);
/// 0, 1, true, false (and True, False).
[[nodiscard]] std::optional<bool> to_bool(std::string_view cell);

}  // namespace tachi::common
