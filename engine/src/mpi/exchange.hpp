#pragma once
// Particles between ranks outside the halo: from the leader to their first owner at the start,
// to their new owner after a sub-step (LAMMPS's exchange), and back to the leader for the output.
#include <cstdint>
#include <vector>

#include "mpi/local_particles.hpp"
#include "mpi/slabs.hpp"
#include "world.hpp"

namespace particle::detail::mpi {

// collective: this rank's particles, those whose slab is its own. `run` is the run's World on
// rank 0, which sends each other rank its particles; the others receive them (their `run` has
// no arrays). No rank but the leader ever holds more than its own particles and a message.
void distribute(const World& run, const Slabs& slabs, LocalParticles& mine);

// collective: every own particle (mine has no halo) whose centre now lies in another rank's slab
// moves there. A particle may cross any number of slabs in a sub-step. `leaving`: scratch kept
// from sub-step to sub-step (the slots that leave).
void exchange(LocalParticles& mine, const Slabs& slabs, std::vector<std::uint32_t>& leaving);

// collective: every rank's own particles into `out`, the run's World on rank 0 (the others'
// `out` is not read), at their ids, with everything they carry.
void collect(const LocalParticles& mine, const World& out);

}  // namespace particle::detail::mpi
