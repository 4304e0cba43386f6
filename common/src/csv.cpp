#include "tachi/common/csv.hpp"

#include <charconv>
#include <cmath>
#include <type_traits>

namespace tachi::common {
namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

template <class T>
std::optional<T> parse_whole(std::string_view cell) {
  // from_chars takes no '+'; strtod did, and hand-written files have it. "+-1" stays an error.
  if (std::is_floating_point_v<T> && cell.size() > 1 && cell[0] == '+' && cell[1] != '-') cell.remove_prefix(1);
  T value{};
  const auto [ptr, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (cell.empty() || ec != std::errc{} || ptr != cell.data() + cell.size()) return std::nullopt;
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(value)) return std::nullopt;
  }
  return value;
}

}  // namespace

std::vector<std::string> split_csv_line(std::string_view line) {
  std::vector<std::string> cells;
  for (std::size_t start = 0;;) {
    const std::size_t comma = line.find(',', start);
    cells.emplace_back(trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

CsvReader::CsvReader(std::istream& in) : in_(&in) {
  if (auto first = next()) header_ = std::move(first->cells);
}

std::optional<std::size_t> CsvReader::column(std::string_view name) const {
  for (std::size_t i = header_.size(); i-- > 0;)
    if (header_[i] == name) return i;
  return std::nullopt;
}

std::optional<CsvRow> CsvReader::next() {
  std::string line;
  while (std::getline(*in_, line)) {
    ++line_;
    if (!trim(line).empty()) return CsvRow{line_, split_csv_line(line)};
  }
  return std::nullopt;
}

std::optional<std::int64_t> to_int64(std::string_view cell) { return parse_whole<std::int64_t>(cell); }
std::optional<std::uint64_t> to_uint64(std::string_view cell) { return parse_whole<std::uint64_t>(cell); }
std::optional<double> to_double(std::string_view cell) { return parse_whole<double>(cell); }
std::optional<float> to_float(std::string_view cell) { return parse_whole<float>(cell); }

std::optional<bool> to_bool(std::string_view cell) {
  if (cell == "1" || cell == "true" || cell == "True") return true;
  if (cell == "0" || cell == "false" || cell == "False") return false;
  return std::nullopt;
}

}  // namespace tachi::common
