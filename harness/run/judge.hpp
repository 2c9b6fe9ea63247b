// Judge: `psim check` on an external program's output, once per configuration, and what runs.csv
// keeps of its report (the check columns). The full report stays beside the output as JSON.
#pragma once

#include <functional>
#include <string>

#include "config/expansion.hpp"
#include "run/runner.hpp"

namespace psweep {

struct Judgement {
  std::string verdict;     // exact, consistent, ambiguous, violations, malformed; error: unjudged
  std::string first_step;  // the time unit of the first violation, else empty
  std::string detail;      // one line: the report's summary and its first violation or format error
  double seconds = 0;      // the check's process time
};

// The check columns from `psim check --json`'s report, or an `error` verdict saying why there is
// none (`child`: how psim check ended).
Judgement read_judgement(const std::string& report_json, const ChildResult& child);

// Judges the output at `output` of `run` (an external program's) for the scene at `scene`; the
// report is written to `report`.
using Judge = std::function<Judgement(const RunSpec& run, const std::string& scene,
                                      const std::string& output, const std::string& report)>;

// psim check as a child of its own, within the sweep's timeout, requiring the config's readings
// where it names them; `sub_steps_numbered`: the programs whose output numbers sub-steps.
Judge psim_judge(const std::string& psim, double timeout_s, RequiredReadings reading,
                 std::vector<std::string> sub_steps_numbered);

}  // namespace psweep
