#include "tachi/common/line_journal.hpp"

#include "tachi/common/disk_full.hpp"

#include <stdexcept>

namespace tachi::common {

LineJournal::LineJournal(std::filesystem::path path, const std::string& header, const LineReader& read,
                         std::uintmax_t max_bytes)
    : path_(std::move(path)), max_bytes_(max_bytes) {
  const auto fail = [this](const std::string& what) { return std::runtime_error("journal " + path_.string() + ": " + what); };
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec)) throw fail("is a directory");
  const bool fresh = !std::filesystem::exists(path_, ec) || std::filesystem::file_size(path_, ec) == 0;
  if (!fresh) {
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw fail("cannot read");
    std::string line;
    std::getline(in, line);
    if (line != header)
      throw fail("written by another configuration (\"" + line.substr(0, 120) + "\", this run is \"" + header +
                 "\"); give a new file or delete this one");
    std::size_t number = 1;
    std::string bad;
    std::size_t bad_line = 0;
    while (std::getline(in, line)) {
      ++number;
      // Only the very last line may be torn by a kill mid-write.
      if (!bad.empty()) throw fail("line " + std::to_string(bad_line) + " is corrupt: \"" + bad.substr(0, 80) + "\"");
      const bool complete = !in.eof();  // getline hit a newline
      if (!complete || !read(line)) {
        bad = line.empty() ? std::string("(empty)") : line;
        bad_line = number;
      }
    }
    bytes_ = std::filesystem::file_size(path_, ec);
    if (!bad.empty()) {
      // Drop the torn tail so appends start on a fresh line.
      std::filesystem::resize_file(path_, bytes_ - line.size(), ec);
      bytes_ -= line.size();
    }
  }
  out_.open(path_, std::ios::binary | std::ios::app);
  if (!out_) throw fail("cannot open for appending");
  if (fresh) {
    out_ << header << '\n';
    out_.flush();
    bytes_ = header.size() + 1;
  }
  if (!out_) throw_write_error(path_, "journal " + path_.string() + ": cannot write");
}

bool LineJournal::append(const std::string& line) {
  if (full_) return false;
  if (bytes_ + line.size() + 1 > max_bytes_) {
    full_ = true;
    flush();
    return false;
  }
  out_ << line << '\n';
  bytes_ += line.size() + 1;
  return true;
}

void LineJournal::flush() {
  out_.flush();
  if (!out_) throw_write_error(path_, "journal " + path_.string() + ": write failed");
}

}  // namespace tachi::common
