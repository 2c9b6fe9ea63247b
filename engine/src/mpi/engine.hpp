#pragma once
// The MPI engine's entry points (engines.cpp): mpi/engine.cpp where the build has MPI
// (PARTICLE_MPI), mpi/unavailable.cpp where it has not.
#include <string>

#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail::mpi {

// Why this process cannot run the engine ("" when it can): a build without MPI.
std::string unavailable();

// Rank 0's run over every rank of the job (particle/processes.hpp), from simulate(): it sends each
// rank its share of w and returns w with the final state and the run's report; it alone calls
// params.on_time_unit.
RunReport run(const World& w, const RunOptions& options, const PipelineParams& params);

// Another rank's share of rank 0's run, from particle::follow: the run's World, steps and slow
// factor are rank 0's (threads, profile and stop are this rank's own, in `own`). Its report
// counts nothing: rank 0's has the run's counters.
RunReport follow(const PipelineParams& own);

}  // namespace particle::detail::mpi
