// Record: one repetition's result, assembled from the child's outcome and its metrics JSON.
// A run that failed, crashed or timed out is still a record (status + error), never an exception.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "run/runner.hpp"
#include "run/simulated.hpp"

namespace psweep {

// psim's --metrics object (docs/architecture.md, "The run record"): the run's facts, and the
// declared metrics as CSV cells. Absent fields stay empty.
struct Metrics {
  std::string engine;
  std::optional<double> wall_s;
  std::string state_hash;
  std::vector<int> cpus;                      // one per thread, as reported
  std::map<std::string, std::string> values;  // declared metric key -> cell text

  std::string value(const std::string& key) const;  // empty when absent
};

// Reads the run's facts and every metric `declaration` lists, each from its section and checked
// against its type. Throws std::runtime_error saying what is wrong (not JSON, not an object, a
// field of the wrong type).
Metrics parse_metrics(const std::string& text, const Declaration& declaration);

// too_much_output: an external program printed beyond the most its scene's output can hold.
enum class Status { ok, failed, timeout, crashed, too_much_output };
const char* to_string(Status status);

struct Record {
  const RunSpec* run = nullptr;
  int rep = 0;
  Status status = Status::ok;
  std::optional<int> exit_code;  // empty when killed by a signal or the timeout
  double process_s = 0;
  double user_s = 0, sys_s = 0;
  long max_rss_kb = 0;
  long voluntary_switches = 0, involuntary_switches = 0;
  EventCounts events;  // with the rusage fallbacks already applied
  // Where instructions, cache_misses and branch_misses came from: "hardware", "simulated"
  // (cachegrind, run/simulated.hpp) or "" (nowhere).
  std::string counters_source;
  // The configuration's simulated counts whenever it was simulated, beside the hardware's where
  // the machine counted too, so that the two can be compared (runs.csv's simulated_* columns).
  std::optional<SimulatedCounts> simulated;
  std::optional<Metrics> metrics;  // psim's; never an external program's
  bool program = false;            // an external program ran, not psim
  bool oversubscribed = false;
  // An external program's run: how many more tasks were running than when the sweep began, after
  // psweep's wait for quiet (quiet_wait_s); 0 when it started on a machine as quiet. Empty for
  // psim's runs, which psweep does not wait for.
  std::optional<int> busy_tasks;
  std::string node;  // where it ran (node_name(): a Slurm node, else the host)
  // `psim check` on an external program's output, once per configuration (the row it judged):
  // the verdict, the time unit of the first violation, one line of what it found.
  std::string check, check_first_step, check_detail;
  std::string error;  // one line, empty when ok

  // The time to compare: psim's simulation loop; a program has no timer of its own, so its whole
  // process. Empty unless ok.
  std::optional<double> wall_s() const;
};

// `metrics_text` is the metrics file's content, empty when the child wrote none.
Record make_record(const RunSpec& run, int rep, const ChildResult& child,
                   const std::string& metrics_text, double timeout_s, int online_cores,
                   const Declaration& declaration);

// An external program's run: its outcome and measurements, and whether its output reached
// `output_limit` bytes (the kernel stopped it there: too_much_output). No engine metrics.
Record make_program_record(const RunSpec& run, int rep, const ChildResult& child,
                           std::uint64_t output_bytes, std::uint64_t output_limit, double timeout_s,
                           int online_cores);

// The last lines of a stderr text as one line (newlines -> " | ", control characters -> space),
// at most `max_chars` long.
std::string error_tail(const std::string& text, std::size_t max_chars = 300);

// `what`, then the child's stderr tail (error_tail) after ": " where it said anything.
std::string with_tail(const std::string& what, const ChildResult& child);

}  // namespace psweep
