#include "tachi/sensor/hand_csv.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <ostream>
#include <stdexcept>

#include "tachi/common/csv.hpp"

namespace tachi::sensor {
namespace {

/// A CSV read by column name, with errors that name the file, line and column.
class CsvTable {
 public:
  CsvTable(const std::filesystem::path& file, const std::vector<std::string>& required)
      : file_(file.string()), in_(file), csv_(in_) {
    if (!in_.is_open()) throw std::runtime_error(file_ + ": cannot open");
    if (csv_.header().empty()) throw std::runtime_error(file_ + ": empty file (expected a header line)");
    for (const auto& name : required)
      if (!has(name)) throw std::runtime_error(file_ + ": header has no \"" + name + "\" column");
    while (auto row = csv_.next()) rows_.push_back(std::move(*row));
  }
  std::size_t size() const { return rows_.size(); }
  bool has(const std::string& column) const { return csv_.column(column).has_value(); }
  double number(std::size_t row, const std::string& column) const {
    const auto v = common::to_double(text(row, column));
    if (!v) fail(row, column, "not a number");
    return *v;
  }
  std::int64_t integer(std::size_t row, const std::string& column) const {
    const auto v = common::to_int64(text(row, column));
    if (!v) fail(row, column, "not an integer");
    return *v;
  }
  bool flag(std::size_t row, const std::string& column) const {
    const std::int64_t v = integer(row, column);
    if (v != 0 && v != 1) fail(row, column, "must be 0 or 1");
    return v == 1;
  }

 private:
  const std::string& text(std::size_t row, const std::string& column) const {
    const auto& cells = rows_[row].cells;
    const std::size_t i = *csv_.column(column);  // required, or checked with has()
    if (i >= cells.size()) fail(row, column, "missing");
    return cells[i];
  }
  [[noreturn]] void fail(std::size_t row, const std::string& column, const char* why) const {
    throw std::runtime_error(file_ + ": line " + std::to_string(rows_[row].line) + ", column \"" + column + "\": " + why);
  }
  std::string file_;
  std::ifstream in_;
  common::CsvReader csv_;  // reads in_: declared after it
  std::vector<common::CsvRow> rows_;
};

}  // namespace

void write_hand_row(std::ostream& out, std::uint64_t frame, std::int64_t stamp_ns, const HandObservation& hand) {
  char buf[256];
  if (hand.tracked) {
    std::snprintf(buf, sizeof buf, "%llu,%lld,%.6f,%.6f,%.6f,%.3f,%.3f,1,%.4f\n", static_cast<unsigned long long>(frame),
                  static_cast<long long>(stamp_ns), hand.position_m.x(), hand.position_m.y(), hand.position_m.z(),
                  hand.u, hand.v, hand.confidence);
  } else {
    std::snprintf(buf, sizeof buf, "%llu,%lld,0,0,0,0,0,0,0\n", static_cast<unsigned long long>(frame),
                  static_cast<long long>(stamp_ns));
  }
  out << buf;
}

std::vector<HandRow> read_hand_csv(const std::filesystem::path& file) {
  const CsvTable t(file, {"frame", "stamp_ns", "x", "y", "z", "u", "v", "tracked", "confidence"});
  std::vector<HandRow> rows(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    auto& r = rows[i];
    r.frame = static_cast<std::uint64_t>(t.integer(i, "frame"));
    r.stamp_ns = t.integer(i, "stamp_ns");
    r.position = {t.number(i, "x"), t.number(i, "y"), t.number(i, "z")};
    r.u = t.number(i, "u");
    r.v = t.number(i, "v");
    r.tracked = t.flag(i, "tracked");
    r.confidence = t.number(i, "confidence");
  }
  return rows;
}

std::vector<TruthRow> read_truth_csv(const std::filesystem::path& file) {
  const CsvTable t(file, {"frame", "x", "y", "z", "visible"});
  std::vector<TruthRow> rows(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    auto& r = rows[i];
    r.frame = static_cast<std::uint64_t>(t.integer(i, "frame"));
    if (t.has("stamp_ns")) r.stamp_ns = t.integer(i, "stamp_ns");
    r.position = {t.number(i, "x"), t.number(i, "y"), t.number(i, "z")};
    r.visible = t.flag(i, "visible");
  }
  return rows;
}

Evaluation evaluate(const std::vector<HandRow>& hands, const std::vector<TruthRow>& truth) {
  std::map<std::uint64_t, const HandRow*> by_frame;
  for (const auto& h : hands) by_frame[h.frame] = &h;
  Evaluation e;
  e.truth_frames = truth.size();
  std::vector<double> errors;
  for (const auto& t : truth) {
    const auto it = by_frame.find(t.frame);
    if (it == by_frame.end()) {
      ++e.missing_frames;
      if (t.visible) ++e.visible;
      continue;
    }
    const HandRow& h = *it->second;
    if (t.visible) {
      ++e.visible;
      if (h.tracked) {
        ++e.tracked_visible;
        errors.push_back((h.position - t.position).norm());
      }
    } else if (h.tracked) {
      ++e.phantoms;
    }
  }
  e.tracked_ratio = e.visible ? static_cast<double>(e.tracked_visible) / static_cast<double>(e.visible) : 1.0;
  if (!errors.empty()) {
    double sum = 0;
    for (const double x : errors) sum += x * x;
    e.rms_m = std::sqrt(sum / static_cast<double>(errors.size()));
    e.max_m = *std::max_element(errors.begin(), errors.end());
    auto mid = errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2);
    std::nth_element(errors.begin(), mid, errors.end());
    e.median_m = *mid;
  }
  return e;
}

}  // namespace tachi::sensor
