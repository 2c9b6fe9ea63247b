// Schedule: the order in which repetitions run.
//
// Warm-up rounds first (each configuration once per round, not recorded), then round k runs
// repetition k of every configuration. Each round visits the configurations in a fresh shuffled
// order from a fixed-seed generator, so slow drift of the machine (thermal, frequency, other
// tenants) spreads over all configurations instead of lining up with one. The shuffle does not
// depend on what is already done, so a resumed sweep keeps the original order and only skips.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace psweep {

struct Job {
  std::size_t run;  // index into the expansion
  int rep;          // repetition number, or the warm-up number when warmup is true
  bool warmup;
};

// `done(run, rep)` says a recorded repetition exists already (resume). Warm-ups are scheduled only
// for configurations that still have a repetition to run.
std::vector<Job> make_schedule(std::size_t runs, int repetitions, int warmup, std::uint64_t seed,
                               const std::function<bool(std::size_t, int)>& done);

constexpr std::uint64_t schedule_seed = 3210;

}  // namespace psweep
