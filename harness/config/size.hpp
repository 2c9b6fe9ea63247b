// Size of a sweep: how many configurations and runs, per engine, and how long they would take at
// the cost model's estimate (shard.hpp). One lazy pass over the expansion, so even 10^7
// configurations are counted in constant memory; it serves `--dry-run --count` and the guard
// that stops a sweep too big for one machine before anything is written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "config/config.hpp"
#include "config/shard.hpp"

namespace psweep {

struct SweepSize {
  struct Tally {
    std::size_t configurations = 0;
    double seconds = 0;  // warm-ups and repetitions, on one machine
  };
  std::map<std::string, Tally> engines;  // by engine name
  Tally total;
  std::int64_t largest_T = 1;
  std::int64_t largest_P = 0;  // 0: no run of P ranks (no engine that uses P)
  std::int64_t cpus = 0;  // the cost model's: CPUs the estimate shares threads over, 0: ideal
};

// The configurations whose position in the expansion `keep` accepts, at `model`'s estimate.
SweepSize measure(const Config& config, const Declaration& declaration,
                  const std::function<bool(std::size_t index)>& keep, const CostModel& model);

// The --dry-run --count report: one line per engine, the total, the largest P where a run has
// ranks, the largest T (its last line, "largest T: 8", is what scripts/slurm/submit.sh reads for
// --cpus-per-task).
std::string size_report(const Config& config, const SweepSize& size);

// Throws ConfigError when `configurations` x repetitions exceeds config.max_runs and `confirmed`
// (--yes) is not set, saying how long the runs would take (when `seconds` is not negative: not
// yet measured) and how to go ahead.
void check_size(const Config& config, std::size_t configurations, double seconds, bool confirmed,
                const std::string& what);

}  // namespace psweep
