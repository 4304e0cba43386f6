// Parses a tachi-sim command line in-process with one of its flag groups (sim/flags.cpp); CLI::ParseError on a bad one.
#pragma once

#include "tachi/common/app.hpp"

#include <string>
#include <vector>

namespace tachi::sim::test {
template <class Options, class AddFlags>
Options parse_flags(AddFlags add_flags, std::vector<std::string> args) {
  CLI::App app;
  Options options;
  add_flags(app, options);
  args.insert(args.begin(), "tachi-sim");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  app.parse(static_cast<int>(argv.size()), argv.data());
  return options;
}
}  // namespace tachi::sim::test
