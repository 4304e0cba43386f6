// A scratch folder for one test, removed with everything in it when the object goes (also when an
// assertion failed). Named <tag>_<pid>_<n>, so parallel ctest processes and tests never share one.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>

namespace tachi::test {

class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag)
      : path_(std::filesystem::temp_directory_path() /
              ("tachi_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(next_id()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const noexcept { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  static unsigned next_id() {
    static std::atomic<unsigned> counter{0};
    return counter++;
  }
  std::filesystem::path path_;
};

}  // namespace tachi::test
