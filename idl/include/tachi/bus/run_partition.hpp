// Isolation of the runs on one domain: every writer and reader of a process joins the DDS
// partition named by its run id, which `tachi run` passes to its nodes in the environment variable
// TACHI_RUN_ID. Writers and readers match only within one partition, so a node never receives another
// run's samples and needs no per-sample check. Bus tools read every run (partition "*", which matches
// every partition including the default one) unless given one run id.
#pragma once

#include <string>

namespace tachi::bus {

inline constexpr const char* kRunIdEnv = "TACHI_RUN_ID";

/// "tachi.run.<id>" when TACHI_RUN_ID is set (read once, at the first writer or reader), else "" (the default partition).
std::string run_partition();

/// This process's readers match the writers of every run (a bus tool: `tachi echo`, `hz`, `record`, ...).
void read_every_run();

}  // namespace tachi::bus
