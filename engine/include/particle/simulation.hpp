#pragma once
#include <cstdint>
#include <functional>

#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "particle/scene.hpp"

namespace particle {

// If given, called after every whole time unit 1..S-1 with the state at that time (psim gives one
// in print mode and for --state-at; it costs a conversion of the state per time unit).
using StepObserver = std::function<void(std::int64_t step, const Particles&)>;

// Advances scene.particles by scene.steps time units with the model of docs/model.md, "The
// model", or fewer when options.stop is set during the run (RunReport::interrupted, time_reached).
// Throws std::invalid_argument for options it cannot honour (unknown engine, bad K or G).
RunReport simulate(Scene& scene, const RunOptions& options, const StepObserver& observer = {});

// A follower's share of the run its leader (rank 0) started with simulate() (the mpi engine,
// particle/processes.hpp): the leader sends this rank its particles and the run's parameters; the
// follower holds no scene and writes nothing. The report's counters and physics are the leader's
// alone; a follower's tells only whether the run was interrupted.
RunReport follow(const RunOptions& options);

}  // namespace particle
