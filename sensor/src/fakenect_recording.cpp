#include "tachi/sensor/fakenect_recording.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace tachi::sensor {
namespace {

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

template <class T>
bool parse_uint(std::string_view s, T& out) {
  if (!all_digits(s)) return false;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc{} && ptr == s.data() + s.size();
}

/// "1700000000.033333" -> ns, exact (fakenect prints "%f"; any number of decimals up to 9 is accepted).
bool parse_host_time(std::string_view s, std::int64_t& ns) {
  const auto dot = s.find('.');
  const std::string_view whole = s.substr(0, dot);
  const std::string_view frac = dot == std::string_view::npos ? std::string_view{} : s.substr(dot + 1);
  std::int64_t seconds = 0;
  if (!parse_uint(whole, seconds) || seconds > 9'000'000'000LL) return false;
  std::int64_t frac_ns = 0;
  if (dot != std::string_view::npos) {
    if (frac.empty() || frac.size() > 9 || !all_digits(frac)) return false;
    for (std::size_t i = 0; i < 9; ++i) frac_ns = frac_ns * 10 + (i < frac.size() ? frac[i] - '0' : 0);
  }
  ns = seconds * 1'000'000'000LL + frac_ns;
  return true;
}

const char* extension_of(EntryKind kind) {
  switch (kind) {
    case EntryKind::Depth: return "pgm";
    case EntryKind::Colour: return "ppm";
    case EntryKind::Accel: return "dump";
  }
  return "";
}

}  // namespace

std::optional<IndexEntry> parse_index_line(std::string_view line, std::string* why) {
  const auto fail = [&](const char* reason) -> std::optional<IndexEntry> {
    if (why) *why = reason;
    return std::nullopt;
  };
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() < 7 || line[1] != '-') return fail("expected <d|r|a>-<hosttime>-<timestamp>.<pgm|ppm|dump>");
  if (line.find('/') != std::string_view::npos) return fail("a file name must not contain '/'");
  IndexEntry e{};
  switch (line[0]) {
    case 'd': e.kind = EntryKind::Depth; break;
    case 'r': e.kind = EntryKind::Colour; break;
    case 'a': e.kind = EntryKind::Accel; break;
    default: return fail("kind must be d, r or a");
  }
  const std::string_view rest = line.substr(2);
  const auto dash = rest.find('-');
  const auto dot = rest.rfind('.');
  if (dash == std::string_view::npos || dot == std::string_view::npos || dot < dash)
    return fail("expected <d|r|a>-<hosttime>-<timestamp>.<pgm|ppm|dump>");
  if (!parse_host_time(rest.substr(0, dash), e.host_time_ns)) return fail("bad host time");
  if (!parse_uint(rest.substr(dash + 1, dot - dash - 1), e.device_timestamp)) return fail("bad device timestamp");
  if (rest.substr(dot + 1) != extension_of(e.kind)) return fail("extension does not match the kind (d: pgm, r: ppm, a: dump)");
  e.file = std::string(line);
  return e;
}

std::vector<IndexEntry> read_index(const std::filesystem::path& dir) {
  const auto index_path = dir / "INDEX.txt";
  std::ifstream in(index_path, std::ios::binary);
  if (!in) throw RecordingError("recording " + dir.string() + ": cannot open INDEX.txt (is this a fakenect recording?)");
  std::vector<IndexEntry> entries;
  std::string line;
  std::size_t number = 0;
  bool any_depth = false;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    std::string why;
    auto e = parse_index_line(line, &why);
    if (!e) {
      std::string shown = line.substr(0, 80);
      for (char& c : shown)
        if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
      throw RecordingError("recording " + dir.string() + ": INDEX.txt line " + std::to_string(number) + " \"" + shown +
                           "\": " + why);
    }
    const std::string where = "recording " + dir.string() + ": INDEX.txt line " + std::to_string(number) + " lists " + e->file;
    std::error_code ec;
    const auto status = std::filesystem::status(dir / e->file, ec);
    if (!std::filesystem::exists(status)) throw RecordingError(where + ", which does not exist");
    if (!std::filesystem::is_regular_file(status)) throw RecordingError(where + ", which is not a regular file");
    // fakenect-record writes the index as the frames arrive: host time never goes back.
    if (!entries.empty() && e->host_time_ns < entries.back().host_time_ns)
      throw RecordingError(where + ": host time goes back (after " + entries.back().file + "; INDEX.txt out of order?)");
    if (e->kind == EntryKind::Accel) {
      const auto size = std::filesystem::file_size(dir / e->file, ec);
      if (size != kAccelDumpBytes)
        throw RecordingError(where + ", which is " + std::to_string(size) + " bytes; an accelerometer dump is " +
                             std::to_string(kAccelDumpBytes) + " (freenect_raw_tilt_state)");
    }
    any_depth = any_depth || e->kind == EntryKind::Depth;
    entries.push_back(std::move(*e));
  }
  if (!any_depth) throw RecordingError("recording " + dir.string() + ": INDEX.txt lists no depth frames");
  return entries;
}

std::variant<std::monostate, DepthFileError> decode_depth_pgm(std::span<const char> bytes,
                                                              std::vector<std::uint16_t>& raw) {
  // Header: "P5" <ws> width <ws> height <ws> maxval <one ws>; '#' comments allowed between tokens.
  std::size_t pos = 0;
  const auto skip_space = [&] {
    while (pos < bytes.size()) {
      const char c = bytes[pos];
      if (c == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos;
      } else {
        break;
      }
    }
  };
  const auto token = [&]() -> std::string_view {
    skip_space();
    const std::size_t start = pos;
    while (pos < bytes.size() && pos - start < 16 && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    return {bytes.data() + start, pos - start};
  };
  if (bytes.size() < 2 || bytes[0] != 'P' || bytes[1] != '5')
    return DepthFileError{"bad header: not a binary PGM (expected \"P5 640 480 65535\")"};
  pos = 2;
  int width = 0, height = 0, maxval = 0;
  if (!parse_uint(token(), width) || !parse_uint(token(), height) || !parse_uint(token(), maxval))
    return DepthFileError{"bad header: expected \"P5 640 480 65535\""};
  if (width != kDepthWidth || height != kDepthHeight)
    return DepthFileError{"bad header: frame is " + std::to_string(width) + "x" + std::to_string(height) +
                          ", expected 640x480 (FREENECT_RESOLUTION_MEDIUM)"};
  if (maxval < 2047 || maxval > 65535)
    return DepthFileError{"bad header: maxval " + std::to_string(maxval) + ", expected 65535 (16-bit samples)"};
  if (pos >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[pos])))
    return DepthFileError{"bad header: no whitespace after maxval"};
  ++pos;
  constexpr std::size_t kDataBytes = static_cast<std::size_t>(kDepthPixels) * 2;
  if (bytes.size() - pos < kDataBytes)
    return DepthFileError{"truncated: " + std::to_string(bytes.size() - pos) + " of " + std::to_string(kDataBytes) +
                          " data bytes"};
  if (bytes.size() - pos > kDataBytes)
    return DepthFileError{"trailing garbage: " + std::to_string(bytes.size() - pos - kDataBytes) +
                          " bytes after the " + std::to_string(kDataBytes) + " data bytes"};
  raw.resize(kDepthPixels);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + pos);
  // fakenect stores host (little-endian) order; decoded explicitly on a big-endian host. Branch-free
  // with a 16-bit count per block, so that the compiler vectorises it: 35 us per frame instead of
  // 94 us with a branch per sample (~9% of tachi-sensor's time).
  constexpr std::size_t kBlock = 4096;  // a 16-bit count cannot overflow within a block
  std::size_t out_of_range = 0;
  for (std::size_t base = 0; base < static_cast<std::size_t>(kDepthPixels); base += kBlock) {
    const std::size_t end = std::min(static_cast<std::size_t>(kDepthPixels), base + kBlock);
    std::uint16_t block_count = 0;
    for (std::size_t i = base; i < end; ++i) {
      std::uint16_t v = 0;
      if constexpr (std::endian::native == std::endian::little) {
        std::memcpy(&v, data + 2 * i, 2);
      } else {
        v = static_cast<std::uint16_t>(data[2 * i] | (data[2 * i + 1] << 8));
      }
      block_count = static_cast<std::uint16_t>(block_count + (v > kNoReading));
      raw[i] = v > kNoReading ? kNoReading : v;
    }
    out_of_range += block_count;
  }
  if (out_of_range > static_cast<std::size_t>(kDepthPixels) / 100)
    return DepthFileError{std::to_string(out_of_range) +
                          " values exceed 11 bits: not fakenect raw disparity (a big-endian PGM?)"};
  return std::monostate{};
}

void read_depth_file(const std::filesystem::path& file, std::vector<std::uint16_t>& raw, std::vector<char>& scratch) {
  // POSIX I/O into the caller's buffer: an ifstream and a fresh 614 KB vector per frame cost more
  // than decoding (page faults and brk calls in every frame).
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw RecordingError(file.string() + ": cannot open");
  // Header (<= ~64 bytes, more with comments) + data; read a little more to tell "too long" apart from
  // "exact". A file longer than that is garbage after the data whatever its header: say how much.
  constexpr std::size_t kMaxBytes = static_cast<std::size_t>(kDepthPixels) * 2 + 4096;
  struct stat st {};
  if (::fstat(fd, &st) == 0 && static_cast<std::size_t>(st.st_size) > kMaxBytes) {
    ::close(fd);
    throw RecordingError(file.string() + ": trailing garbage: " + std::to_string(st.st_size) + " bytes, a depth frame is " +
                         std::to_string(static_cast<std::size_t>(kDepthPixels) * 2) + " plus a short header");
  }
  scratch.resize(kMaxBytes);
  std::size_t got = 0;
  while (got < scratch.size()) {
    const ssize_t n = ::read(fd, scratch.data() + got, scratch.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  const auto result = decode_depth_pgm(std::span<const char>(scratch.data(), got), raw);
  if (const auto* err = std::get_if<DepthFileError>(&result)) throw RecordingError(file.string() + ": " + err->message);
}

std::string format_host_time(std::int64_t host_time_ns) {
  // "%f" of a double rounds to microseconds; do it in integers so names are reproducible.
  const std::int64_t us = (host_time_ns + 500) / 1000;
  std::array<char, 48> buf{};
  std::snprintf(buf.data(), buf.size(), "%lld.%06lld", static_cast<long long>(us / 1'000'000),
                static_cast<long long>(us % 1'000'000));
  return buf.data();
}

FakenectWriter::FakenectWriter(const std::filesystem::path& dir) : dir_(dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw RecordingError("record " + dir_.string() + ": cannot create folder: " + ec.message());
  const auto index_path = dir_ / "INDEX.txt";
  if (std::filesystem::exists(index_path))
    throw RecordingError("record " + dir_.string() + ": INDEX.txt already exists; use a new folder");
  index_.open(index_path, std::ios::binary);
  if (!index_) throw RecordingError("record " + dir_.string() + ": cannot create INDEX.txt");
}

FakenectWriter::~FakenectWriter() { index_.flush(); }

std::string FakenectWriter::add_entry(char kind, std::int64_t host_time_ns, std::uint32_t device_timestamp,
                                      const char* extension) {
  std::string name = std::string(1, kind) + "-" + format_host_time(host_time_ns) + "-" +
                     std::to_string(device_timestamp) + "." + extension;
  index_ << name << '\n';
  return name;
}

void FakenectWriter::write_depth(const DepthFrame& frame) {
  if (frame.raw.size() != static_cast<std::size_t>(kDepthPixels))
    throw RecordingError("record " + dir_.string() + ": depth frame has " + std::to_string(frame.raw.size()) +
                         " pixels, expected 307200");
  static constexpr char kHeader[] = "P5 640 480 65535\n";
  buffer_.resize(sizeof kHeader - 1 + static_cast<std::size_t>(kDepthPixels) * 2);
  std::memcpy(buffer_.data(), kHeader, sizeof kHeader - 1);
  auto* out = reinterpret_cast<unsigned char*>(buffer_.data() + sizeof kHeader - 1);
  for (std::size_t i = 0; i < frame.raw.size(); ++i) {
    out[2 * i] = static_cast<unsigned char>(frame.raw[i] & 0xff);
    out[2 * i + 1] = static_cast<unsigned char>(frame.raw[i] >> 8);
  }
  // Write the file before listing it, so a reader never sees a listed file that is not there.
  const std::string name = "d-" + format_host_time(frame.stamp_ns) + "-" + std::to_string(frame.device_timestamp) + ".pgm";
  std::ofstream f(dir_ / name, std::ios::binary);
  f.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  if (!f) throw RecordingError("record " + dir_.string() + ": cannot write " + name);
  f.close();
  index_ << name << '\n';
  if (!index_) throw RecordingError("record " + dir_.string() + ": cannot write INDEX.txt");
  ++depth_frames_;
}

void FakenectWriter::write_accel(std::int64_t host_time_ns, std::uint32_t device_timestamp, const AccelSample& accel) {
  // freenect_raw_tilt_state: int16 x, y, z; int8 tilt_angle; (pad); int32 tilt_status, little-endian.
  std::array<unsigned char, 12> b{};
  const auto put16 = [&](std::size_t at, std::int16_t v) {
    b[at] = static_cast<unsigned char>(static_cast<std::uint16_t>(v) & 0xff);
    b[at + 1] = static_cast<unsigned char>(static_cast<std::uint16_t>(v) >> 8);
  };
  put16(0, accel.ax);
  put16(2, accel.ay);
  put16(4, accel.az);
  b[6] = static_cast<unsigned char>(accel.tilt_angle);
  const auto status = static_cast<std::uint32_t>(accel.tilt_status);
  for (std::size_t i = 0; i < 4; ++i) b[8 + i] = static_cast<unsigned char>((status >> (8 * i)) & 0xff);
  const std::string name = "a-" + format_host_time(host_time_ns) + "-" + std::to_string(device_timestamp) + ".dump";
  std::ofstream f(dir_ / name, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  if (!f) throw RecordingError("record " + dir_.string() + ": cannot write " + name);
  f.close();
  index_ << name << '\n';
}

void FakenectWriter::flush() { index_.flush(); }

}  // namespace tachi::sensor
