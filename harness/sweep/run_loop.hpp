// Run loop: the third stage of a sweep. Runs the scheduled jobs one at a time, each as a fresh
// child, and keeps the results folder current: every recorded repetition is appended to runs.csv
// and summary.csv rewritten as soon as the child ends, so an interrupt or a crash loses no
// finished row. Warm-ups run but are not recorded. It stops at the first interrupted child (not a
// result: --resume runs it again) or when SIGINT/SIGTERM arrived.
//
// The child is started through `Launch`, so the loop can be tested with a stand-in for psim.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "results/stats.hpp"
#include "run/counters.hpp"
#include "run/runner.hpp"
#include "sweep/schedule.hpp"

namespace psweep {

// Each run's input file: its scene_file, or out/inputs/<id>.in, written here, holding the random
// scene's header.
std::vector<std::string> write_inputs(const std::vector<RunSpec>& runs,
                                      const std::filesystem::path& out);

// Starts one child for `run` reading `input` and writing its metrics to `metrics_file`.
using Launch = std::function<ChildResult(const RunSpec& run, const std::string& input,
                                         const std::string& metrics_file)>;

// psim under run_child (timeout, counters, the run's environment), with a busy neighbour for the
// run's lifetime when its `neighbour` parameter asks for one.
Launch psim_launcher(const std::string& psim, double timeout_s,
                     const CounterAvailability* counters);

struct LoopSetup {
  const Config* config = nullptr;
  const Declaration* declaration = nullptr;  // the runs.csv columns and the metrics to read
  const std::vector<RunSpec>* runs = nullptr;
  std::vector<std::string> inputs;  // per run (write_inputs)
  std::filesystem::path out;        // runs.csv, summary.csv; tmp/ for the metrics files
  int cores = 0;                    // online CPUs: a run of more threads is oversubscribed
};

struct LoopTotals {
  std::size_t finished = 0;  // jobs that ran to an outcome, warm-ups included
  std::size_t not_ok = 0;    // of which failed, crashed or timed out
  double children_s = 0;     // the children's lifetimes, fork to reap
  double wall_s = 0;         // the loop's
};

// Runs `jobs` (make_schedule's) in order; `recorded` (the resumed rows) grows by each recorded
// repetition. Writes summary.csv before the first job, so the folder is complete at every moment.
LoopTotals run_loop(const LoopSetup& setup, const std::vector<Job>& jobs, const Launch& launch,
                    std::vector<RecordedRun>& recorded);

}  // namespace psweep
