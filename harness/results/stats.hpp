// Statistics: pure functions over plain values, no I/O.
//
// The summary keeps the minimum wall time as the headline (noise on a shared machine only ever
// adds time), with median and maximum to show the spread. Only `ok` repetitions count.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace psweep {

// Preconditions: non-empty. Median of an even count is the mean of the two middle values.
double minimum(const std::vector<double>& values);
double median(std::vector<double> values);
double maximum(const std::vector<double>& values);

// What the summary needs from one recorded repetition (a new run or a row of runs.csv).
struct RecordedRun {
  std::string config_id;
  int rep = 0;
  bool ok = false;
  std::optional<double> wall_s;
  bool checked = false;  // holds an external program's check (its configuration is judged)
  std::optional<double> builds_per_substep;  // psim's runs (builds_per_substep below)
};

struct Summary {
  int reps = 0;    // ok repetitions with a wall time
  int failed = 0;  // repetitions with another status
  std::optional<double> wall_min, wall_median, wall_max;
  std::optional<double> builds_per_substep;  // of the repetition with wall_min
};

// Summarizes the rows whose config_id is `id`.
Summary summarize(const std::vector<RecordedRun>& runs, const std::string& id);

// The broad phase's builds per sub-step of a run, from its metrics' cells broad_phase_builds and
// time_reached and its K: 1 where it builds every sub-step, less where it keeps its structure.
// Empty where a cell is empty or not a number, or the run reached no sub-step.
std::optional<double> builds_per_substep(const std::string& builds, const std::string& time_reached,
                                         std::optional<std::int64_t> slow_factor);

// A particle-step's own state, four doubles read (x, y, ux, uy) and two written (x, y): the bytes
// a loop at the memory floor moves (analysis/plots/ceilings.py's STATE_BYTES).
inline constexpr double kStateBytes = 48;

// The rate at which a loop of `particle_steps` (N x S x K) in `wall_s` goes through that state,
// in GB/s: the figure to set against the machine's triad bandwidth. Empty without a positive time
// or a known N.
std::optional<double> state_gb_per_s(double particle_steps, std::optional<double> wall_s);

}  // namespace psweep
