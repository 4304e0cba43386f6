// tachi-pipeline: the pipeline's stages in one process (`tachi run --in-process`), each the node class its
// own executable runs, on its own thread and participant, over the same DDS bus: stages.cpp builds them
// from their executables' flags, common::run_composed runs them until the finite ones are done or a signal.
#include "src/stages.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/disk_full.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::common::install_stop_handlers();  // before the stages' journal replays, which a stop must not kill midway
  tachi::pipeline::Composition composition;
  if (const int rc = tachi::pipeline::compose(argc, argv, composition); rc >= 0) return rc;
  return tachi::common::run_composed(std::move(composition.nodes), composition.grace);
} catch (const tachi::common::DiskFull& e) {
  std::cerr << "tachi-pipeline: " << e.what() << '\n';  // the one line a full disk gets; tachi run does not restart it
  return tachi::common::kExitDiskFull;
} catch (const std::exception& e) {
  std::cerr << "tachi-pipeline: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
