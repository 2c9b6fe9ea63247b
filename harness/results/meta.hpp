// Meta: provenance of a sweep (meta.json), so a CSV can be traced to code, build and machine.
#pragma once

#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "run/counters.hpp"

namespace psweep {

struct MetaInputs {
  const Config* config = nullptr;
  std::string psim;
  const Declaration* declaration = nullptr;  // psim --describe
  std::vector<std::string> command_line;
  CounterAvailability counters;
  int online_cores = 0;
  Json ceilings;  // results/ceilings.hpp: this machine's, or null
};

// config, psim's declaration (engines and metrics, for the analysis), git commit + dirty flag,
// compiler and flags, CPU model, cores, kernel, OpenMP runtime, date, the counter note and the
// machine's ceilings. Runs
// `git` once; missing facts become null, never an error.
Json build_meta(const MetaInputs& inputs);

// The config's external programs as they run: command, input, uses, the K of one built for one,
// the executable found and a hash of its bytes (null where it cannot be read).
Json programs_meta(const Config& config);

// The Slurm job this process runs in (job id, array job id and task id from Slurm's environment),
// null outside Slurm.
Json slurm_job();

// The node this process runs on: Slurm's name for it (SLURMD_NODENAME) inside a job, else the
// hostname. Several Slurm nodes may share one host, so the hostname alone does not say which.
std::string node_name();

// The current time as ISO 8601 UTC.
std::string utc_now();

}  // namespace psweep
