#include "tachi/sensor/playback_progress.hpp"

#include "tachi/common/disk_full.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace tachi::sensor {
namespace {
constexpr std::size_t kDigits = 20;  // any uint64_t
constexpr std::size_t kLineBytes = kDigits + 1;

std::runtime_error error(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error("playback progress " + path.string() + ": " + what);
}
}  // namespace

PlaybackProgress::PlaybackProgress(std::filesystem::path path) : path_(std::move(path)) {
  if (std::filesystem::is_directory(path_)) throw error(path_, "is a directory");
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw error(path_, std::strerror(errno));
  char line[kLineBytes + 1] = {};
  const ssize_t n = ::pread(fd_, line, kLineBytes + 1, 0);
  if (n < 0) {
    const int err = errno;
    ::close(fd_);
    throw error(path_, std::strerror(err));
  }
  if (n == 0) {  // a new file: nothing played yet. Its line is written now, so that later rewrites in place need no new room
    record(0);
    return;
  }
  const bool well_formed = n == static_cast<ssize_t>(kLineBytes) && line[kDigits] == '\n' &&
                           std::strspn(line, "0123456789") == kDigits;
  if (!well_formed) {
    ::close(fd_);
    throw error(path_, "expected one line of 20 digits (frames published); remove the file to play from the top");
  }
  resumed_after_ = std::stoull(std::string(line, kDigits));
}

PlaybackProgress::~PlaybackProgress() {
  if (fd_ >= 0) ::close(fd_);
}

void PlaybackProgress::record(std::uint64_t frames_published) {
  char line[kLineBytes + 1];
  std::snprintf(line, sizeof line, "%020llu\n", static_cast<unsigned long long>(frames_published));
  if (::pwrite(fd_, line, kLineBytes, 0) != static_cast<ssize_t>(kLineBytes))
    common::throw_write_error(path_, "playback progress " + path_.string() + ": " + std::strerror(errno));
}

}  // namespace tachi::sensor
