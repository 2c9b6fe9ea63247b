// psweep confined: one command run as a submission's program runs, in the strongest tier this
// machine allows (run/tier.hpp), under the default limits: what `make grade` builds a folder of
// sources with (analysis/grade/build.py), so that a Makefile is someone else's code too.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace psweep {

struct ConfinedOptions {
  std::vector<std::string> command;  // argv[0] a path or a name on PATH; files it names staged
  std::string stdout_path;           // its stdout; empty: /dev/null
  double timeout_s = 120;
  std::uint64_t stdout_bytes = 0;    // RLIMIT_FSIZE: every file it writes; 0: none
  bool unconfined = false;
};

// Runs it; its stderr's tail goes to psweep's stderr. Exit status: the command's, 128 + n when
// signal n ended it, 124 when it timed out, 2 when it cannot be run (said on stderr).
int run_confined(const ConfinedOptions& options);

}  // namespace psweep
