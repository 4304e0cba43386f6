// tachi-sim: the cloth simulator process. --offline runs the library's offline driver; the live
// (DDS) mode will be added by the pipeline work.
#include "tachi/common/app.hpp"

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  CLI::App app{"tachi-sim: mass-spring cloth simulator (Provot), collisions, grabbing, cutting"};
  app.name("tachi-sim");
  bool offline = false;
  std::string log_level = "info";
  app.add_flag("--offline", offline, "Run without DDS: simulate, then export the mesh and a summary");
  tachi::common::add_log_level_flag(app, log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  if (!offline) {
    std::cerr << "tachi-sim: live mode needs the DDS pipeline: not built yet; use --offline\n";
    return tachi::common::kExitUsage;
  }
  std::cerr << "tachi-sim: offline driver not built yet\n";
  return tachi::common::kExitFailure;
} catch (const std::exception& e) {
  std::cerr << "tachi-sim: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
