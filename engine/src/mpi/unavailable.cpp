// The MPI engine in a build without MPI (PARTICLE_MPI=OFF, or AUTO where CMake found no MPI):
// declared like every engine, refused with the reason when asked to run; a process is then a job
// of one (particle/processes.hpp).
#include "mpi/engine.hpp"
#include "particle/io.hpp"
#include "particle/processes.hpp"

namespace particle {
namespace detail::mpi {

std::string unavailable() {
  return "this build has no MPI (PARTICLE_MPI=OFF, or no MPI found: install openmpi-bin and "
         "libopenmpi-dev, as scripts/bootstrap.sh does, and rebuild)";
}

// simulate() asks unavailable() first; a caller that did not still gets the reason.
RunReport run(const World&, const RunOptions&, const PipelineParams&) {
  throw InputError("engine mpi: " + unavailable());
}
RunReport follow(const PipelineParams&) { throw InputError("engine mpi: " + unavailable()); }

}  // namespace detail::mpi

Processes join_processes() { return {}; }
void start_followers() {}
std::optional<int> await_leader() { return 0; }  // never called: there is no follower
void call_off(int) {}
void fail_processes(int) {}

}  // namespace particle
