// Run loop: the third stage of a sweep. Runs the scheduled jobs one at a time, each as a fresh
// child, and keeps the results folder current: every recorded repetition is appended to runs.csv
// and summary.csv rewritten as soon as the child ends, so an interrupt or a crash loses no
// finished row. Warm-ups run but are not recorded. An external program's first recorded ok run
// of each configuration is judged by psim check; its output and report stay in out/outputs/. It
// stops at the first interrupted child (not a result: --resume runs it again) or when
// SIGINT/SIGTERM arrived.
//
// The child is started through `Launch`, so the loop can be tested with a stand-in for psim.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "results/stats.hpp"
#include "run/confine.hpp"
#include "run/counters.hpp"
#include "run/judge.hpp"
#include "run/runner.hpp"
#include "run/simulated.hpp"
#include "run/tier.hpp"
#include "sweep/schedule.hpp"

namespace psweep {

// Each run's input file: its scene_file, or out/inputs/<id>.in, written here, holding the random
// scene's header.
std::vector<std::string> write_inputs(const std::vector<RunSpec>& runs,
                                      const std::filesystem::path& out);

// An external program's scenes for one run: what its timed runs read, and what its judging run
// reads (docs/programs.md, "The check").
struct ProgramScene {
  std::uint64_t output_limit = 0;  // the most bytes a timed run's output may take
  std::size_t particles = 0;       // N: the lines of a final state
  // The scene in print mode (S capped at the config's judge_steps, if given), judged step by
  // step; empty when the timed runs' scene is itself print mode (their output is judged so).
  std::string judge_input;
  std::uint64_t judge_limit = 0;
  bool whole = false;  // the judging run is the whole scene: the timed runs' final state is its
};

// An external program's scene, for each of its runs: `inputs` (write_inputs') replaced by the
// scene psim draws from them, written with every particle (psim --write-scene) to
// out/inputs/<id>-particles.in, once per distinct scene, and beside it the judging scene
// <id>-judge.in. Returns, per run, its ProgramScene (all empty for psim's runs). Throws
// std::runtime_error when psim cannot write a scene.
std::vector<ProgramScene> write_program_scenes(const Config& config,
                                               const std::vector<RunSpec>& runs,
                                               std::vector<std::string>& inputs,
                                               const std::filesystem::path& out,
                                               const std::string& psim);

// What one child reads and writes: psim its metrics, an external program its output (bounded).
struct RunFiles {
  std::string input;    // the scene
  std::string metrics;  // psim's --metrics
  std::string output;   // an external program's stdout
  std::uint64_t output_limit = 0;
};

// Starts one child for `run`.
using Launch = std::function<ChildResult(const RunSpec& run, const RunFiles& files)>;

// psim, or the external program `config` declares under the run's engine name, under run_child
// (timeout, counters, the run's environment), with a busy neighbour for the run's lifetime when
// its `neighbour` parameter asks for one. A program runs confined by `tier` (run/tier.hpp),
// pinned to its T CPUs; with no tier (--unconfined) it runs as psweep's user, in psweep's
// folder, with its environment.
Launch child_launcher(const Config& config, const std::string& psim,
                      const CounterAvailability* counters, Tier* tier);

struct LoopSetup {
  const Config* config = nullptr;
  const Declaration* declaration = nullptr;  // the runs.csv columns and the metrics to read
  const std::vector<RunSpec>* runs = nullptr;
  std::vector<std::string> inputs;           // per run (write_inputs, write_program_scenes)
  std::filesystem::path out;                 // runs.csv, summary.csv; tmp/ for the metrics files
  int cores = 0;                             // online CPUs: a run of more threads is oversubscribed
  std::string node;                          // each row's node column (node_name())
  std::vector<ProgramScene> program_scenes;  // per run (write_program_scenes); empty: none
  Judge judge;                               // external programs' outputs (psim_judge)
  // counters: "simulate": each configuration's simulated counts by config id (simulate.hpp)
  std::map<std::string, SimulatedCounts> simulated;
};

struct LoopTotals {
  std::size_t finished = 0;  // jobs that ran to an outcome, warm-ups included
  std::size_t not_ok = 0;    // of which failed, crashed or timed out
  double children_s = 0;     // the children's lifetimes, fork to reap
  double checks_s = 0;       // psim check on external programs' outputs
  double wall_s = 0;         // the loop's
};

// Runs `jobs` (make_schedule's) in order; `recorded` (the resumed rows) grows by each recorded
// repetition. Writes summary.csv before the first job, so the folder is complete at every moment.
LoopTotals run_loop(const LoopSetup& setup, const std::vector<Job>& jobs, const Launch& launch,
                    std::vector<RecordedRun>& recorded);

}  // namespace psweep
