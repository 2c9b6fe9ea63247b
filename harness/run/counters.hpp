// Counters: Linux perf events on a child process, opened before it execs.
//
// Each event is its own fd (inherit = 1 follows the child's OpenMP threads; inherited counters
// cannot be read as a group), disabled until exec (enable_on_exec), so the harness's fork and
// handshake are not counted. Values are scaled by time_enabled/time_running when the kernel
// multiplexed hardware counters. Software events: task-clock, context-switches, cpu-migrations,
// page-faults. Hardware events (cycles, instructions, branches, branch-misses, cache-misses) exist
// only where the kernel offers them (not in most VMs): their cells stay empty there.
// Cost: 9 perf_event_open calls and 9 reads per run, tens of microseconds.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace psweep {

struct EventCounts {
  std::optional<double> task_clock_s;
  std::optional<std::uint64_t> context_switches;
  std::optional<std::uint64_t> cpu_migrations;
  std::optional<std::uint64_t> page_faults;
  std::optional<std::uint64_t> cycles;
  std::optional<std::uint64_t> instructions;
  std::optional<std::uint64_t> branches;
  std::optional<std::uint64_t> branch_misses;
  std::optional<std::uint64_t> cache_misses;
};

// What this machine allows, probed once on the harness itself (the child runs as the same user).
struct CounterAvailability {
  bool software = false;
  bool hardware = false;
  bool user_only = false;  // kernel.perf_event_paranoid forced exclude_kernel
  std::string note;        // human-readable, for meta.json
};

CounterAvailability probe_counters();

// The counters of one child. open() before the child execs; read() after it was reaped.
class ChildCounters {
 public:
  ChildCounters() = default;
  ChildCounters(const ChildCounters&) = delete;
  ChildCounters& operator=(const ChildCounters&) = delete;
  ~ChildCounters();

  void open(pid_t child, const CounterAvailability& available);
  EventCounts read() const;

 private:
  std::vector<int> fds_;  // one per entry of the event table; -1 = not available
};

}  // namespace psweep
