// Simulated counters, a stage before the run loop (config `counters: "simulate"`, docs/sweeps.md):
// each psim configuration that has repetitions left to run goes once through make regress's
// scripts/psim-cachegrind, its cache and branch simulation on and sized as this machine's
// caches (run/simulated.hpp); the run loop fills its rows' empty counters from the counts.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/expansion.hpp"
#include "run/simulated.hpp"
#include "sweep/schedule.hpp"

namespace psweep {

// Why a sweep cannot simulate here, "" when it can: this build's AVX-512 (simulation_refused) or
// no valgrind on PATH.
std::string cannot_simulate();

// By config id, the counts of each psim configuration that `jobs` (make_schedule's) run, read
// from its input (write_inputs') as the timed runs read it; scratch in out/tmp/counts/. A
// configuration whose simulated run failed has none, said on stderr with the run's error.
std::map<std::string, SimulatedCounts> simulate_counters(
    const Config& config, const std::vector<RunSpec>& runs, const std::vector<Job>& jobs,
    const std::vector<std::string>& inputs, const std::string& out, const std::string& psim);

}  // namespace psweep
