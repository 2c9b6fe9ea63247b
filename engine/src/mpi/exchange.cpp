// Migration and output (mpi/exchange.hpp): one all-to-all of 64-byte records for the particles
// that change owner, one gather of every particle for a printed time unit and the end.
#include "mpi/exchange.hpp"

#include <vector>

#include "broad_phase/cell_order.hpp"
#include "mpi/comm.hpp"

namespace particle::detail::mpi {

// In cell order (broad_phase/cell_order.hpp), as the cells engine keeps its arrays: the cell
// index's counting sort then writes each record next to the previous one, not to a random place
// (on the million-particle crowd at P = 1, id order made the sort 39% of the loop and the run 3 to
// 4.8 times the cells engine's). Slots are not ids: the order and orientation go by id.
void take_own_particles(const World& run, const Slabs& slabs, LocalParticles& mine) {
  const int me = this_rank();
  for (const std::uint32_t i : cell_order(run))
    if (slabs.owner(run.x[i]) == me)
      mine.add_owned({run.x[i], run.y[i], run.ux[i], run.uy[i], run.wall_impulse[i],
                      run.pair_collisions[i], run.wall_collisions[i],
                      static_cast<std::uint32_t>(i)});
}

void exchange(LocalParticles& mine, const Slabs& slabs, std::vector<int>& destination) {
  const int ranks = rank_count(), me = this_rank();
  std::vector<int> counts(static_cast<std::size_t>(ranks), 0);
  destination.resize(mine.owned());
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
  const auto put = [&run](const Record& r) {
    run.x[r.id] = r.x;
    run.y[r.id] = r.y;
    run.ux[r.id] = r.ux;
    run.uy[r.id] = r.uy;
    run.wall_impulse[r.id] = r.wall_impulse;
    run.pair_collisions[r.id] = r.pair_collisions;
    run.wall_collisions[r.id] = r.wall_collisions;
  };
  const int ranks = rank_count(), me = this_rank();
  // One rank holds every particle: no message, and no copy of the state (at N = 10^6 the two
  // copies of 64-byte records were 128 MB and a fifth of the loop, mostly the kernel zeroing
  // their pages).
  if (ranks == 1) {
    for (std::size_t slot = 0; slot < mine.owned(); ++slot) put(mine.record(slot));
    return;
  }
  const int count = static_cast<int>(mine.owned());
  std::vector<int> counts(static_cast<std::size_t>(ranks));
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  const std::vector<int> at = displacements(counts);
  // A receiving rank writes its own records where the gather puts them and sends them in place.
  const bool receives = everywhere || me == 0;
  std::vector<Record> records(receives ? run.n : mine.owned());
  Record* own = records.data() + (receives ? at[static_cast<std::size_t>(me)] : 0);
  for (std::size_t slot = 0; slot < mine.owned(); ++slot) own[slot] = mine.record(slot);
  const MPI_Datatype type = record_type<Record>();
  if (everywhere)
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, records.data(), counts.data(), at.data(),
                   type, MPI_COMM_WORLD);
  else if (receives)
    MPI_Gatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, records.data(), counts.data(), at.data(), type,
                0, MPI_COMM_WORLD);
  else
    MPI_Gatherv(records.data(), count, type, nullptr, nullptr, nullptr, type, 0, MPI_COMM_WORLD);
  if (receives)
    for (const Record& r : records) put(r);
}

}  // namespace particle::detail::mpi
