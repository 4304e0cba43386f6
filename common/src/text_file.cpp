#include "tachi/common/text_file.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tachi::common {

std::string read_text_file(const std::filesystem::path& path, std::string_view what) {
  // A directory opens as an ifstream and reads as empty: say what it is instead.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::runtime_error("cannot read " + std::string(what) + " " + path.string() + ": is a directory");
  if (!std::filesystem::exists(path, ec))
    throw std::runtime_error("cannot read " + std::string(what) + " " + path.string() + ": no such file");
  std::ifstream in(path);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || in.bad()) throw std::runtime_error("cannot read " + std::string(what) + " " + path.string());
  return text.str();
}

}  // namespace tachi::common
