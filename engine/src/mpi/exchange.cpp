// Migration and output (mpi/exchange.hpp): one all-to-all of 64-byte records for the particles
// that change owner, one gather of every particle for a printed time unit and the end.
#include "mpi/exchange.hpp"

#include <vector>

#include "mpi/comm.hpp"

namespace particle::detail::mpi {

void take_own_particles(const World& run, const Slabs& slabs, LocalParticles& mine) {
  const int me = this_rank();
  for (std::size_t i = 0; i < run.n; ++i)
    if (slabs.owner(run.x[i]) == me)
      mine.add_owned({run.x[i], run.y[i], run.ux[i], run.uy[i], run.wall_impulse[i],
                      run.pair_collisions[i], run.wall_collisions[i],
                      static_cast<std::uint32_t>(i)});
}

void exchange(LocalParticles& mine, const Slabs& slabs) {
  const int ranks = rank_count(), me = this_rank();
  std::vector<int> counts(static_cast<std::size_t>(ranks), 0);
  std::vector<int> destination(mine.owned());
  for (std::size_t slot = 0; slot < mine.owned(); ++slot) {
    destination[slot] = slabs.owner(mine.x[slot]);
    if (destination[slot] != me) ++counts[static_cast<std::size_t>(destination[slot])];
  }
  std::vector<int> at = displacements(counts);
  std::vector<Record> leaving(static_cast<std::size_t>(at.back() + counts.back())), arriving;
  for (std::size_t slot = 0; slot < mine.owned(); ++slot)
    if (destination[slot] != me)
      leaving[static_cast<std::size_t>(at[static_cast<std::size_t>(destination[slot])]++)] =
          mine.record(slot);
  all_to_all(leaving, counts, arriving);
  mine.keep_owned_if([&](std::size_t slot) { return destination[slot] == me; });
  for (const Record& r : arriving) mine.add_owned(r);
}

void collect(const LocalParticles& mine, const World& run, bool everywhere) {
  const int ranks = rank_count();
  std::vector<Record> own(mine.owned()), all(everywhere || this_rank() == 0 ? run.n : 0);
  for (std::size_t slot = 0; slot < mine.owned(); ++slot) own[slot] = mine.record(slot);
  const int count = static_cast<int>(own.size());
  std::vector<int> counts(static_cast<std::size_t>(ranks));
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  const std::vector<int> at = displacements(counts);
  if (everywhere)
    MPI_Allgatherv(own.data(), count, record_type<Record>(), all.data(), counts.data(), at.data(),
                   record_type<Record>(), MPI_COMM_WORLD);
  else
    MPI_Gatherv(own.data(), count, record_type<Record>(), all.data(), counts.data(), at.data(),
                record_type<Record>(), 0, MPI_COMM_WORLD);
  for (const Record& r : all) {
    run.x[r.id] = r.x;
    run.y[r.id] = r.y;
    run.ux[r.id] = r.ux;
    run.uy[r.id] = r.uy;
    run.wall_impulse[r.id] = r.wall_impulse;
    run.pair_collisions[r.id] = r.pair_collisions;
    run.wall_collisions[r.id] = r.wall_collisions;
  }
}

}  // namespace particle::detail::mpi
