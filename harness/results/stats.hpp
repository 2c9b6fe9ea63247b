// Statistics: pure functions over plain values, no I/O.
//
// The summary keeps the minimum wall time as the headline (noise on a shared machine only ever
// adds time), with median and maximum to show the spread. Only `ok` repetitions count.
#pragma once

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
};

struct Summary {
  int reps = 0;    // ok repetitions with a wall time
  int failed = 0;  // repetitions with another status
  std::optional<double> wall_min, wall_median, wall_max;
};

// Summarizes the rows whose config_id is `id`.
Summary summarize(const std::vector<RecordedRun>& runs, const std::string& id);

}  // namespace psweep
