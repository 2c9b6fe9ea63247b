// Sweep: config -> expansion -> schedule -> runner -> runs.csv / summary.csv / meta.json, in four
// stages each testable alone: plan (plan.hpp: what runs, --dry-run, the size guard), resume
// (resume.hpp: what the folder already holds), the run loop (run_loop.hpp) and finish (finish.hpp:
// the session's cost, the exit status). run_sweep calls them in order. Exit status: 0 when every
// scheduled job ran (failed runs are rows, not errors), 2 for a bad config or command line, 1 for
// an I/O or internal error, 128 + signal when interrupted (finished rows are kept; --resume
// completes the sweep).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace psweep {

struct SweepOptions {
  std::string config_path;
  std::optional<std::string> out_dir;  // default results/<name>
  std::optional<std::string> psim;     // default $PSIM, else psim next to psweep
  bool resume = false;
  bool force = false;  // with resume: although the config's expansion differs from the folder's
  bool dry_run = false;
  bool count = false;                // with dry_run: the size per engine, no listing
  bool yes = false;                  // go ahead with more runs than the config's max_runs
  std::optional<std::string> shard;  // "I/N": only shard I of N (config/shard.hpp)
  bool unconfined = false;  // external programs run as the user, unconfined (run/confine.hpp)
  std::optional<std::string> counters;  // "hardware" or "simulate": the config's `counters` overridden
  std::vector<std::string> command_line;
};

int run_sweep(const SweepOptions& options);

}  // namespace psweep
