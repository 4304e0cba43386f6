#include "tachi/sim/options.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <string_view>

#include <sys/resource.h>

namespace tachi::sim {
namespace {

constexpr int kMaxGrid = 4096;

std::optional<int> parse_int(std::string_view s) {
  int value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  return value;
}

}  // namespace

std::optional<std::pair<int, int>> parse_grid(const std::string& text) {
  const auto x = text.find_first_of("xX");
  const auto columns = parse_int(std::string_view{text}.substr(0, x));
  const auto rows = x == std::string::npos ? columns : parse_int(std::string_view{text}.substr(x + 1));
  if (!columns || !rows) return std::nullopt;
  if (*columns < 2 || *rows < 2 || *columns > kMaxGrid || *rows > kMaxGrid) return std::nullopt;
  return std::pair{*columns, *rows};
}

SessionOptions session_options(const OfflineOptions& o) {
  SessionOptions s;
  s.cloth = o.cloth;
  s.solver = o.solver;
  s.solver_kind = o.solver_kind;
  if (o.material) {
    s.material = *o.material;
    apply_material(*o.material, s.cloth, s.solver);
  }
  if (!o.substeps_given) s.solver.substeps = SolverParams{}.substeps;
  if (o.substeps_given) s.provot.substeps = o.solver.substeps;
  s.stroke.blade = o.blade;
  s.blade_force_n = o.blade_force_n;
  s.stroke.mode = o.cut_mode;
  s.object = o.object;
  return s;
}

std::uint64_t available_memory_bytes() {
  std::uint64_t available = 0;
  std::ifstream meminfo{"/proc/meminfo"};
  std::string key;
  std::uint64_t kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit) {
    if (key == "MemAvailable:") {
      available = kb * 1024;
      break;
    }
  }
  // An address-space limit (ulimit -v) binds before physical memory does.
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    available = available == 0 ? limit.rlim_cur : std::min<std::uint64_t>(available, limit.rlim_cur);
  return available;
}

std::optional<std::string> memory_shortfall(int columns, int rows) {
  const double need = kPeakBytesPerParticle * static_cast<double>(columns) * static_cast<double>(rows);
  const auto available = static_cast<double>(available_memory_bytes());
  if (available <= 0.0 || need <= available) return std::nullopt;
  char text[200];
  std::snprintf(text, sizeof text, "a %dx%d cloth needs about %.1f GB and this machine has %.1f GB available; use a smaller grid",
                columns, rows, need / 1e9, available / 1e9);
  return text;
}

}  // namespace tachi::sim
