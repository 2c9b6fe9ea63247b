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

// This rank's share of one run over every rank of the job (particle/processes.hpp). Every rank
// passes the same World; each returns it with the final state and the same report; rank 0 alone
// calls params.on_time_unit.
RunReport run(const World& w, const RunOptions& options, const PipelineParams& params);

}  // namespace particle::detail::mpi
