// The mpi engine installed in a test program before its tests run, as psim-mpi installs it
// (particle/processes.hpp): linked, with particle_mpi, into the tests that run the engine in
// their own process where the build has MPI.
#include "particle/processes.hpp"

namespace {
const bool installed = (particle::install_mpi_engine(), true);
}  // namespace
