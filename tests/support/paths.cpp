#include "paths.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace tachi::test {
namespace {

const std::map<std::string, std::string>& paths_file() {
  static const std::map<std::string, std::string> paths = [] {
    const auto file = std::filesystem::path(bin_dir()) / "tachi_test_paths.txt";
    std::ifstream in(file);
    if (!in) throw std::runtime_error("cannot read " + file.string() + " (written by CMake at configure time)");
    std::map<std::string, std::string> kv;
    for (std::string line; std::getline(in, line);)
      if (const auto eq = line.find('='); eq != std::string::npos) kv[line.substr(0, eq)] = line.substr(eq + 1);
    return kv;
  }();
  return paths;
}

const std::string& path(const std::string& key) {
  const auto& kv = paths_file();
  const auto it = kv.find(key);
  if (it == kv.end()) throw std::runtime_error("tachi_test_paths.txt has no " + key);
  return it->second;
}

}  // namespace

const std::string& bin_dir() {
  static const std::string dir = std::filesystem::read_symlink("/proc/self/exe").parent_path().string();
  return dir;
}

std::string executable(const std::string& name) { return bin_dir() + "/" + name; }
const std::string& recordings_dir() { return path("recordings"); }
const std::string& source_dir() { return path("source"); }
const std::string& binary_dir() { return path("binary"); }

}  // namespace tachi::test
