// No lost cuts (docs/reliability.md): how far a recording's playback got, kept in a small
// file, so a sensor killed mid-run and started again (tachi run restarts it) continues after the last
// frame it published instead of playing the recording from the top, which would cut the stroke twice.
//
// Format: one line, the number of frames published, as 20 digits and a newline, rewritten in place
// after every published frame (one pwrite of 21 bytes; a SIGKILL cannot tear it). No fsync: the file
// outlives the process, not the machine.
#pragma once

#include <cstdint>
#include <filesystem>

namespace tachi::sensor {

class PlaybackProgress {
 public:
  /// Opens (creating) `path` and reads the count already there (0 for a new or empty file).
  /// Throws std::runtime_error naming the file when it cannot be opened or holds anything else.
  explicit PlaybackProgress(std::filesystem::path path);
  ~PlaybackProgress();
  PlaybackProgress(const PlaybackProgress&) = delete;
  PlaybackProgress& operator=(const PlaybackProgress&) = delete;

  /// Frames an earlier run published: the ones to catch up on (unpublished) before going on.
  [[nodiscard]] std::uint64_t resumed_after() const noexcept { return resumed_after_; }
  /// Records that `frames_published` frames have gone out. Throws naming the file when the write fails.
  void record(std::uint64_t frames_published);
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::uint64_t resumed_after_ = 0;
};

}  // namespace tachi::sensor
