#include "tachi/common/disk_full.hpp"

#include <cerrno>
#include <system_error>

namespace tachi::common {

bool out_of_space(const std::filesystem::path& file, int saved_errno) {
  if (saved_errno == ENOSPC || saved_errno == EDQUOT) return true;
  std::error_code ec;
  const auto dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  const auto space = std::filesystem::space(dir, ec);
  constexpr std::uintmax_t kNearlyFull = 64 * 1024;  // less than one stream buffer's worth of blocks
  return !ec && space.available < kNearlyFull;
}

void throw_write_error(const std::filesystem::path& file, const std::string& message) {
  const int saved = errno;
  if (out_of_space(file, saved)) throw DiskFull(file);
  throw std::runtime_error(message);
}

}  // namespace tachi::common
