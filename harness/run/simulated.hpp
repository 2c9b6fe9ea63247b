// Simulated counters (config `counters: "simulate"`, docs/sweeps.md): where perf_event offers
// no hardware events (most VMs), each configuration runs once more under valgrind's cachegrind,
// through scripts/psim-cachegrind (make regress's), with its cache and branch simulation on and
// the caches sized as this machine's, and the counts fill the runs' empty instructions,
// cache_misses (last level) and branch_misses. Deterministic, unlike a timing, so once per
// configuration suffices; about 50 times slower than the run itself.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "run/counters.hpp"

namespace psweep {

struct SimulatedCounts {
  std::uint64_t instructions = 0;   // Ir
  std::uint64_t ll_misses = 0;      // ILmr + DLmr + DLmw: the last level's misses
  std::uint64_t branch_misses = 0;  // Bcm + Bim: conditional and indirect
};

// From a cachegrind output file's `events:` and `summary:` lines; nullopt when either is
// missing or the simulation was off (no LL or branch events).
std::optional<SimulatedCounts> parse_cachegrind(const std::string& text);

// cachegrind's options for this machine: --cache-sim=yes --branch-sim=yes and --I1, --D1, --LL
// from the caches under `sysfs` (size, ways, line), each size rounded down to a power-of-two
// number of sets, which cachegrind requires; a cache sysfs lacks is left to cachegrind's own
// guess.
std::string cachegrind_options(const std::string& sysfs = "/sys/devices/system/cpu/cpu0/cache");

// Why this psweep's build cannot run under valgrind here, "" when it can: valgrind 3.19 cannot
// decode AVX-512, which a -march=native build on an AVX-512 CPU uses (psim and psweep are one
// CMake build: make regress's build-regress/, or make build BUILD=DIR AVX512=0, is one without).
std::string simulation_refused();

// The counters of a run: the hardware's where it counted them ("hardware"), else the simulated
// ones of its configuration ("simulated"), else none (""). Returns the counters_source cell.
std::string fill_counters(EventCounts& events, const SimulatedCounts* simulated);

}  // namespace psweep
