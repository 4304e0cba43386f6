// tachi: the one command. `tachi run` starts and supervises the pipeline's processes and leaves the
// run's outputs in a folder; `tachi topics|echo|hz|bw|status` show what is on a domain's bus and
// `tachi record|play` record it into MCAP and publish it again (docs/cli.md "tachi").
#include "src/cli.hpp"
#include "src/commands.hpp"
#include "tachi/common/disk_full.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::launcher::Command command;
  if (const int rc = tachi::launcher::parse_command(argc, argv, command); rc >= 0) return rc;
  return tachi::launcher::dispatch(command, tachi::launcher::self_dir(argv[0]));
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi: " << e.what() << '\n';
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
