// psim-mpi: psim with the mpi engine and MPI's libraries linked in, what `psim --engine mpi`
// becomes (particle/processes.hpp, docs/architecture.md). Built only with MPI (PARTICLE_MPI).
#include "particle/processes.hpp"
#include "psim.hpp"

int main(int argc, char** argv) {
  particle::install_mpi_engine();
  return psim_main(argc, argv);
}
