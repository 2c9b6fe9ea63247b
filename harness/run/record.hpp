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

enum class Status { ok, failed, timeout, crashed };
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
  std::optional<Metrics> metrics;
  bool oversubscribed = false;
  std::string error;  // one line, empty when ok
};

// `metrics_text` is the metrics file's content, empty when the child wrote none.
Record make_record(const RunSpec& run, int rep, const ChildResult& child,
                   const std::string& metrics_text, double timeout_s, int online_cores,
                   const Declaration& declaration);

// The last lines of a stderr text as one line (newlines -> " | ", control characters -> space),
// at most `max_chars` long.
std::string error_tail(const std::string& text, std::size_t max_chars = 300);

}  // namespace psweep
