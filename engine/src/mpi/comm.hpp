#pragma once
// The MPI engine's messages: records (trivially copyable structs) sent as one MPI type each, so a
// count is a number of records, not of bytes (2^31 records, not 2^31 bytes, per message), and
// the all-to-all exchanges every move of a step is made of. Every function here is collective
// over MPI_COMM_WORLD and called by each rank's main thread alone (MPI_THREAD_FUNNELED).
#include <mpi.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

namespace particle::detail::mpi {

inline int this_rank() {
  int rank;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

inline int rank_count() {
  int count;
  MPI_Comm_size(MPI_COMM_WORLD, &count);
  return count;
}

// What this rank's sub-steps spent on messages, for the run's RankTraffic (particle/profile.hpp):
// one tally per process, since the rank's main thread alone calls MPI; a run clears it first.
struct Tally {
  std::uint64_t bytes_sent = 0;      // payload handed to MPI for other ranks
  std::uint64_t halo_particles = 0;  // copies received (mpi/halo.cpp)
  std::uint64_t filter_rounds = 0;   // (mpi/rounds.cpp)
  double comm_s = 0;                 // in MPI calls
  double wait_s = 0;                 // of those, in the collectives of a few bytes (below)
};
inline Tally& tally() {
  static Tally t;
  return t;
}

// Times one collective into the tally and counts its payload. A `synchronising` one carries a few
// bytes per rank (a maximum, a sum, the counts before an all-to-all): its transfer takes
// microseconds, so its time is the wait for the last rank to arrive, and counts as waiting too.
class Timed {
 public:
  Timed(std::uint64_t bytes, bool synchronising) : synchronising_(synchronising) {
    if (rank_count() > 1) tally().bytes_sent += bytes;  // a job of one sends nobody anything
  }
  ~Timed() {
    const double seconds = MPI_Wtime() - start_;
    tally().comm_s += seconds;
    if (synchronising_) tally().wait_s += seconds;
  }
  Timed(const Timed&) = delete;
  Timed& operator=(const Timed&) = delete;

 private:
  const bool synchronising_;
  const double start_ = MPI_Wtime();
};

// T's bytes as one MPI type, committed on first use and kept for the process.
template <class T>
MPI_Datatype record_type() {
  static_assert(std::is_trivially_copyable_v<T>);
  static const MPI_Datatype type = [] {
    MPI_Datatype t;
    MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &t);
    MPI_Type_commit(&t);
    return t;
  }();
  return type;
}

// Where each rank's part starts in a buffer grouped by rank.
inline std::vector<int> displacements(const std::vector<int>& counts) {
  std::vector<int> at(counts.size(), 0);
  std::exclusive_scan(counts.begin(), counts.end(), at.begin(), 0);
  return at;
}

// Who sends how much to whom: counts per destination rank in, counts per source rank out.
inline std::vector<int> receive_counts(const std::vector<int>& send_counts) {
  std::vector<int> counts(send_counts.size());
  const Timed timed((send_counts.size() - 1) * sizeof(int), true);
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  return counts;
}

// Records grouped by destination rank (send_counts) to their ranks; what arrives, grouped by
// source rank in rank order (counts: how many from each), replaces `received`.
template <class T>
void all_to_all(const std::vector<T>& sent, const std::vector<int>& send_counts,
                const std::vector<int>& counts, std::vector<T>& received) {
  const std::vector<int> send_at = displacements(send_counts), receive_at = displacements(counts);
  received.resize(static_cast<std::size_t>(receive_at.back() + counts.back()));
  // Every move sends nothing to its own rank, so the whole buffer goes to others.
  const Timed timed(sent.size() * sizeof(T), false);
  MPI_Alltoallv(sent.data(), send_counts.data(), send_at.data(), record_type<T>(), received.data(),
                counts.data(), receive_at.data(), record_type<T>(), MPI_COMM_WORLD);
}

// The same where the receivers do not know their counts yet: they go first. Returns them.
template <class T>
std::vector<int> all_to_all(const std::vector<T>& sent, const std::vector<int>& send_counts,
                            std::vector<T>& received) {
  std::vector<int> counts = receive_counts(send_counts);
  all_to_all(sent, send_counts, counts, received);
  return counts;
}

inline std::uint64_t sum_over_ranks(std::uint64_t v) {
  std::uint64_t sum;
  const Timed timed(sizeof v, true);
  MPI_Allreduce(&v, &sum, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  return sum;
}

// The machines the ranks run on, by name: Slurm's inside a Slurm job (SLURMD_NODENAME, which
// slurmd gives every task on its node), else MPI's (the host name). Slurm's first, because
// Slurm's nodes need not be distinct hosts: make test-slurm's nodes n1, n2 and n3 are one
// machine, and only their Slurm names tell a run across them from a run on one of them.
inline std::uint64_t node_count() {
  char name[MPI_MAX_PROCESSOR_NAME] = {};
  if (const char* slurm = std::getenv("SLURMD_NODENAME"); slurm && *slurm) {
    std::string(slurm).copy(name, sizeof name - 1);
  } else {
    int length = 0;
    MPI_Get_processor_name(name, &length);
  }
  std::vector<char> names(static_cast<std::size_t>(rank_count()) * sizeof name);
  MPI_Allgather(name, sizeof name, MPI_CHAR, names.data(), sizeof name, MPI_CHAR, MPI_COMM_WORLD);
  std::set<std::string> distinct;
  for (std::size_t at = 0; at < names.size(); at += sizeof name)
    distinct.emplace(names.data() + at, strnlen(names.data() + at, sizeof name));
  return distinct.size();
}

}  // namespace particle::detail::mpi
