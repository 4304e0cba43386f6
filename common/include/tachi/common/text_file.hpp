// Reading a small text file (a JSON or XML config) whole, with an error that says what it was for.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace tachi::common {

/// Returns the file's contents. Throws std::runtime_error("cannot read <what> <path>") when it cannot be read.
std::string read_text_file(const std::filesystem::path& path, std::string_view what);

}  // namespace tachi::common
