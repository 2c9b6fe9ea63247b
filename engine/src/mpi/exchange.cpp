// Distribution, migration and output (mpi/exchange.hpp): one all-to-all of 64-byte records for
// the particles that change owner, found in one pass of two comparisons a slot; messages of at most
// kChunk records between rank 0 and each other rank at the start, for a printed time unit and at
// the end.
#include "mpi/exchange.hpp"

#include <algorithm>
#include <vector>

#include "broad_phase/cell_order.hpp"
#include "mpi/comm.hpp"
#include "mpi/memory.hpp"

namespace particle::detail::mpi {
namespace {

// Records per message between rank 0 and another rank (2 MB): neither side holds a copy of the
// whole state in flight (at N = 10^6 one copy is 64 MB, more than a rank's share at P = 2).
constexpr std::size_t kChunk = std::size_t{1} << 15;

Record record_of(const World& w, std::uint32_t i) {
  return {w.x[i],
          w.y[i],
          w.ux[i],
          w.uy[i],
          w.wall_impulse[i],
          w.pair_collisions[i],
          w.wall_collisions[i],
          i};
}

void put(const World& w, const Record& r) {
  w.x[r.id] = r.x;
  w.y[r.id] = r.y;
  w.ux[r.id] = r.ux;
  w.uy[r.id] = r.uy;
  w.wall_impulse[r.id] = r.wall_impulse;
  w.pair_collisions[r.id] = r.pair_collisions;
  w.wall_collisions[r.id] = r.wall_collisions;
}

// `count` records from `source` in messages of at most kChunk, each handed to take().
template <class Take>
void receive_records(int source, std::size_t count, Take&& take) {
  std::vector<Record> chunk(std::min(count, kChunk));
  for (std::size_t done = 0; done < count; done += chunk.size()) {
    const auto size = static_cast<int>(std::min(count - done, kChunk));
    MPI_Recv(chunk.data(), size, record_type<Record>(), source, 0, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    for (int k = 0; k < size; ++k) take(chunk[static_cast<std::size_t>(k)]);
  }
}

// The records given by record(k), k < count, to `destination` in messages of at most kChunk.
template <class RecordOf>
void send_records(int destination, std::size_t count, RecordOf&& record) {
  std::vector<Record> chunk;
  chunk.reserve(std::min(count, kChunk));
  for (std::size_t k = 0; k < count; ++k) {
    chunk.push_back(record(k));
    if (chunk.size() == kChunk || k + 1 == count) {
      MPI_Send(chunk.data(), static_cast<int>(chunk.size()), record_type<Record>(), destination, 0,
               MPI_COMM_WORLD);
      chunk.clear();
    }
  }
}

}  // namespace

// In cell order (broad_phase/cell_order.hpp), as the cells engine keeps its arrays: the cell
// index's counting sort then writes each record next to the previous one, not to a random place
// (on the million-particle crowd at P = 1, id order made the sort 39% of the loop and the run 3 to
// 4.8 times the cells engine's). Slots are not ids: the order and orientation go by id.
void distribute(const World& run, const Slabs& slabs, LocalParticles& mine) {
  const int ranks = rank_count(), me = this_rank();
  std::vector<int> counts(static_cast<std::size_t>(ranks), 0);
  std::vector<std::uint32_t> order;
  if (me == 0) {
    order = cell_order(run);
    for (const std::uint32_t i : order) ++counts[static_cast<std::size_t>(slabs.owner(run.x[i]))];
  }
  int count = 0;
  MPI_Scatter(counts.data(), 1, MPI_INT, &count, 1, MPI_INT, 0, MPI_COMM_WORLD);
  mine.reserve(static_cast<std::size_t>(count));
  if (me != 0) {
    receive_records(0, static_cast<std::size_t>(count),
                    [&](const Record& r) { mine.add_owned(r); });
    return;
  }
  const auto of_rank = [&](int rank) {  // in cell order
    std::vector<std::uint32_t> theirs;
    theirs.reserve(static_cast<std::size_t>(counts[static_cast<std::size_t>(rank)]));
    for (const std::uint32_t i : order)
      if (slabs.owner(run.x[i]) == rank) theirs.push_back(i);
    return theirs;
  };
  // Rank 0's own go last, with the order freed: beside the run's arrays, the leader's peak.
  const std::vector<std::uint32_t> own = of_rank(0);
  for (int rank = 1; rank < ranks; ++rank) {
    const std::vector<std::uint32_t> theirs = of_rank(rank);
    send_records(rank, theirs.size(), [&](std::size_t k) { return record_of(run, theirs[k]); });
  }
  order = {};
  return_freed_pages();
  for (const std::uint32_t i : own) mine.add_owned(record_of(run, i));
}

void exchange(LocalParticles& mine, const Slabs& slabs, std::vector<std::uint32_t>& leaving) {
  const int ranks = rank_count(), me = this_rank();
  // Who leaves: those outside this slab, found with owner()'s own comparisons (Slabs::region).
  const Slabs::Interval region = slabs.region(me);
  leaving.clear();
  for (std::size_t slot = 0; slot < mine.owned(); ++slot)
    if (!(mine.x[slot] >= region.lo && mine.x[slot] < region.hi))
      leaving.push_back(static_cast<std::uint32_t>(slot));
  std::vector<int> counts(static_cast<std::size_t>(ranks), 0);
  for (const std::uint32_t slot : leaving)
    ++counts[static_cast<std::size_t>(slabs.owner(mine.x[slot]))];
  std::vector<int> at = displacements(counts);
  std::vector<Record> sent(leaving.size()), arriving;
  for (const std::uint32_t slot : leaving)
    sent[static_cast<std::size_t>(at[static_cast<std::size_t>(slabs.owner(mine.x[slot]))]++)] =
        mine.record(slot);
  all_to_all(sent, counts, arriving);
  mine.replace_owned(leaving, arriving);
}

void collect(const LocalParticles& mine, const World& out) {
  const int ranks = rank_count(), me = this_rank();
  if (me != 0) {
    const auto count = static_cast<int>(mine.owned());
    MPI_Gather(&count, 1, MPI_INT, nullptr, 0, MPI_INT, 0, MPI_COMM_WORLD);
    send_records(0, mine.owned(), [&](std::size_t slot) { return mine.record(slot); });
    return;
  }
  std::vector<int> counts(static_cast<std::size_t>(ranks));
  const auto count = static_cast<int>(mine.owned());
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (std::size_t slot = 0; slot < mine.owned(); ++slot) put(out, mine.record(slot));
  for (int rank = 1; rank < ranks; ++rank)
    receive_records(rank, static_cast<std::size_t>(counts[static_cast<std::size_t>(rank)]),
                    [&](const Record& r) { put(out, r); });
}

}  // namespace particle::detail::mpi
