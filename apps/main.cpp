// psim: every engine in this process but mpi, whose runs psim-mpi beside it takes over; so psim
// loads none of MPI's libraries (particle/processes.hpp, docs/architecture.md).
#include "particle/processes.hpp"
#include "psim.hpp"

int main(int argc, char** argv) {
  particle::delegate_mpi_engine();
  return psim_main(argc, argv);
}
