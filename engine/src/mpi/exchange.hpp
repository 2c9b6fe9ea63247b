#pragma once
// Particles between ranks outside the halo: to their new owner after a sub-step (LAMMPS's
// exchange), and from every rank into the run's World for the output.
#include "mpi/local_particles.hpp"
#include "mpi/slabs.hpp"
#include "world.hpp"

namespace particle::detail::mpi {

// This rank's particles from the run's World, which every rank holds whole at the start: those
// whose slab is this rank's. No message.
void take_own_particles(const World& run, const Slabs& slabs, LocalParticles& mine);

// collective: every own particle (mine has no halo) whose centre now lies in another rank's slab
// moves there. A particle may cross any number of slabs in a sub-step. `destination`: scratch
// kept from sub-step to sub-step (a slot's new owner), not allocated and zeroed afresh each.
void exchange(LocalParticles& mine, const Slabs& slabs, std::vector<int>& destination);

// collective: every rank's own particles into the run's World at their ids, with everything they
// carry: on rank 0 alone, or on every rank (everywhere).
void collect(const LocalParticles& mine, const World& run, bool everywhere);

}  // namespace particle::detail::mpi
