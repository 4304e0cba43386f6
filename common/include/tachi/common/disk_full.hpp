// A full disk is not an ordinary write error: restarting the writer cannot free space, so every writer
// that can meet one (journals, the simulator's export, the viewer's video and snapshots, the launcher's
// trace, summary and recording) throws DiskFull, the process's main logs its one line
// "<file>: no space left on device" and exits kExitDiskFull, and `tachi run` ends the run instead of
// restarting the node (docs/reliability.md, "A full disk").
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace tachi::common {

/// A write that failed because the file's filesystem is full (ENOSPC, or EDQUOT: out of quota).
class DiskFull : public std::runtime_error {
 public:
  explicit DiskFull(const std::filesystem::path& file)
      : std::runtime_error(file.string() + ": no space left on device"), file_(file) {}
  [[nodiscard]] const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

/// True when a write to `file` that just failed failed for want of space: errno says ENOSPC or EDQUOT
/// (read it before any other call), or, since a stream may have lost errno, the file's filesystem has
/// less than 64 KB left for this user.
bool out_of_space(const std::filesystem::path& file, int saved_errno);

/// Throws DiskFull when out_of_space(file, errno), else std::runtime_error(message). Call it right
/// after the failed write, before anything that may change errno.
[[noreturn]] void throw_write_error(const std::filesystem::path& file, const std::string& message);

}  // namespace tachi::common
