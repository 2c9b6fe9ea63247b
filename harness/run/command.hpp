// Command: how one RunSpec becomes a psim invocation (arguments, input text, environment), and
// the psim calls around an external program's runs (its scene, its check).
// Pure functions, so the mapping from config to child process is unit-tested without spawning.
#pragma once

#include <string>
#include <vector>

#include "config/declaration.hpp"
#include "config/expansion.hpp"

namespace psweep {

// The five header lines of a random scene in the 2019 input format (perf mode, no particle lines).
std::string random_scene_input(const Params& params);

// argv for psim; `input` is the scene file or the random-scene input written by the caller.
std::vector<std::string> psim_arguments(const RunSpec& run, const std::string& psim,
                                        const std::string& input, const std::string& metrics_file);

// argv for `psim --write-scene`: the run's scene, drawn from `input` as psim_arguments would have
// psim draw it, written to `scene_file` with every particle (what an external program reads).
std::vector<std::string> write_scene_arguments(const RunSpec& run, const std::string& psim,
                                               const std::string& input,
                                               const std::string& scene_file);

// argv for `psim check SCENE OUTPUT` at the run's K, its full report to `report` (JSON), with
// the readings it requires, if any; for an output that numbers sub-steps
// (Program::sub_steps_numbered), said where K is above 1.
std::vector<std::string> check_arguments(const RunSpec& run, const std::string& psim,
                                         const std::string& scene, const std::string& output,
                                         const std::string& report, const RequiredReadings& reading,
                                         bool sub_steps_numbered);

// The child's environment: the parent's without any OMP_* variable, plus OMP_NUM_THREADS = T and
// OMP_PROC_BIND / OMP_PLACES from the pin policy (close|spread -> bind with places=cores; none ->
// OMP_PROC_BIND=false, OMP_PLACES unset). An engine without T (event) gets no OMP variables. A
// run of P ranks whose T x P threads exceed psweep's CPUs gets OMP_WAIT_POLICY=passive.
std::vector<std::string> child_environment(const RunSpec& run,
                                           const std::vector<std::string>& parent);

// The current process environment as a vector.
std::vector<std::string> current_environment();

// Runs `psim --describe` and parses it; throws std::runtime_error naming psim when it fails.
Declaration ask_psim(const std::string& psim);

}  // namespace psweep
