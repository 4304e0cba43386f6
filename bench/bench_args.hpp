// Positional arguments of the benchmarks that take numbers (cut_bench, provot_bench, render_bench): a
// wrong argument is an error naming it (exit 2), never a benchmark run on a grid of 0 or a crash, and
// --help / -h prints the usage and exits 0.
#pragma once

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace tachi::bench {

/// Exits 0 after printing `usage` when any argument is --help or -h.
inline void exit_on_help(int argc, char** argv, const char* usage) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::fputs(usage, stdout);
      std::exit(0);
    }
  }
}

/// The whole of `text` as an integer in [min, max]; otherwise prints which argument is wrong, and the usage,
/// to stderr and exits 2.
inline int int_argument(const char* text, const char* name, int min, int max, const char* usage) {
  const std::string_view s{text};
  int value = 0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (error != std::errc{} || end != s.data() + s.size() || value < min || value > max) {
    std::fprintf(stderr, "%s: '%s' is not a whole number in %d..%d\n%s", name, text, min, max, usage);
    std::exit(2);
  }
  return value;
}

}  // namespace tachi::bench
