// libfreenect's fakenect recording format (as fakenect-record 0.5.3 writes it and libfreenect's
// fakenect library plays it back): a folder with INDEX.txt listing one file name a line, in order;
//   d-<hosttime>-<timestamp>.pgm  depth: header "P5 640 480 65535\n", then 640*480 uint16 raw
//                                 disparity in little-endian (host) order, despite PGM's rule;
//   r-<hosttime>-<timestamp>.ppm  colour: "P6 640 480 255\n" + RGB bytes;
//   a-<hosttime>-<timestamp>.dump accelerometer: freenect_raw_tilt_state (12 bytes).
// <hosttime> is gettimeofday seconds printed with "%f"; <timestamp> the device's frame counter.
#pragma once

#include "tachi/sensor/depth_frame.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "tachi/sensor/depth_frame.hpp"

namespace tachi::sensor {

/// A recording that cannot be read; what() names the recording, the file or INDEX line, and why.
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class EntryKind : char { Depth = 'd', Colour = 'r', Accel = 'a' };

struct IndexEntry {
  EntryKind kind;
  std::string file;              ///< file name relative to the recording folder
  std::int64_t host_time_ns;     ///< <hosttime> of the name, exactly (no floating-point rounding)
  std::uint32_t device_timestamp;
};

/// Parses one INDEX.txt line ("d-1700000000.033333-1234.pgm"); nullopt with `why` set when it is
/// not a fakenect file name.
std::optional<IndexEntry> parse_index_line(std::string_view line, std::string* why = nullptr);

/// freenect_raw_tilt_state as fakenect-record dumps it.
inline constexpr std::uintmax_t kAccelDumpBytes = 12;

/// Reads <dir>/INDEX.txt. Throws RecordingError on a missing index, a garbage line (naming its
/// number), a listed file that does not exist or is not a file, host times going back, an
/// accelerometer dump of the wrong size, or an index without depth frames.
std::vector<IndexEntry> read_index(const std::filesystem::path& dir);

/// Why a depth file could not be decoded.
struct DepthFileError {
  std::string message;
};

/// Decodes a fakenect depth PGM into `raw` (kDepthPixels values). Values above 2047 in a few
/// pixels become kNoReading; many of them mean the file is big-endian (a real PGM), an error.
std::variant<std::monostate, DepthFileError> decode_depth_pgm(std::span<const char> bytes,
                                                              std::vector<std::uint16_t>& raw);

/// Reads and decodes one depth file; throws RecordingError naming the file. `scratch` holds the
/// file's bytes: passing the same one (and the same `raw`) every frame allocates nothing per frame.
void read_depth_file(const std::filesystem::path& file, std::vector<std::uint16_t>& raw, std::vector<char>& scratch);
inline void read_depth_file(const std::filesystem::path& file, std::vector<std::uint16_t>& raw) {
  std::vector<char> scratch;
  read_depth_file(file, raw, scratch);
}

/// Host time as fakenect prints it ("%f": seconds with six decimals).
std::string format_host_time(std::int64_t host_time_ns);

/// Writes a fakenect recording that libfreenect's fakenect library plays back.
class FakenectWriter {
 public:
  /// Creates `dir` (and parents) and INDEX.txt; refuses a folder that already holds an INDEX.txt,
  /// as fakenect-record does. Throws RecordingError.
  explicit FakenectWriter(const std::filesystem::path& dir);
  ~FakenectWriter();
  FakenectWriter(const FakenectWriter&) = delete;
  FakenectWriter& operator=(const FakenectWriter&) = delete;

  /// Appends a depth frame (frame.raw must hold kDepthPixels values).
  void write_depth(const DepthFrame& frame);
  /// Appends an accelerometer snapshot taken at host time `host_time_ns`.
  void write_accel(std::int64_t host_time_ns, std::uint32_t device_timestamp, const AccelSample& accel);
  /// Flushes INDEX.txt (also done on destruction).
  void flush();
  const std::filesystem::path& dir() const noexcept { return dir_; }
  std::uint64_t depth_frames() const noexcept { return depth_frames_; }

 private:
  std::string add_entry(char kind, std::int64_t host_time_ns, std::uint32_t device_timestamp, const char* extension);
  std::filesystem::path dir_;
  std::ofstream index_;
  std::uint64_t depth_frames_ = 0;
  std::vector<char> buffer_;
};

}  // namespace tachi::sensor
