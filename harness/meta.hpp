// Meta: provenance of a sweep (meta.json), so a CSV can be traced to code, build and machine.
#pragma once

#include <string>
#include <vector>

#include "config.hpp"
#include "counters.hpp"

namespace psweep {

struct MetaInputs {
  const Config* config = nullptr;
  std::string psim;
  std::vector<std::string> engines;  // psim --list-engines
  std::vector<std::string> command_line;
  CounterAvailability counters;
  int online_cores = 0;
};

// config, git commit + dirty flag, compiler and flags, CPU model, cores, kernel, OpenMP runtime,
// date and the counter note. Runs `git` once; missing facts become null, never an error.
Json build_meta(const MetaInputs& inputs);

// The current time as ISO 8601 UTC.
std::string utc_now();

}  // namespace psweep
