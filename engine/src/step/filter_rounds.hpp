#pragma once
// The model's filter (step/filter.cpp) as rounds of independent decisions, one per candidate, for
// engines that cannot walk the order on one thread: the GPU engine runs each stage as a kernel
// (gpu/parallel_step.hpp), the MPI engine on each rank over its own particles' candidates, with a
// halo particle's proposal taken from its owner between the stages (mpi/rounds.cpp). The stages
// are functions of one index, compiled for host and device (PARTICLE_HD).
#include <cstdint>
#include <limits>

#include "host_device.hpp"
#include "particle/replay.hpp"  // Candidate

namespace particle::detail {

inline constexpr std::uint32_t kNoCandidate = std::numeric_limits<std::uint32_t>::max();

// The greedy filter by rounds. Each round, every remaining candidate proposes its rank (its place
// in the total order) to both its particles, keeping the smallest per particle; a candidate that
// is the smallest of both its particles is accepted; then every remaining candidate of an accepted
// particle is dropped. Repeat until none remain.
//
// This accepts exactly what the sequential filter (step/filter.cpp) accepts. By induction over
// the rounds, with R the remaining candidates and the invariant that the sequential filter, run
// over the whole order, accepts the ones accepted so far, takes no particle of R before its
// rank, and rejects the dropped ones:
//  - a candidate c accepted in this round is first among R's candidates of each of its particles;
//    the candidates before it that are not in R were accepted or dropped, and by the invariant
//    none of those took c's particles before c (an accepted one would have dropped c; a dropped
//    one took nothing), so the sequential filter reaches c with both particles free: accepts it;
//  - a candidate d dropped in this round shares a particle with some c accepted in it, and c
//    comes first among R's candidates of that particle, so before d: the sequential filter,
//    having accepted c, rejects d;
//  - the candidates still in R after the round touch no particle accepted so far, so the
//    invariant holds for the next round.
// The first of R in the order is first for both its particles, so each round accepts at least
// one candidate: the rounds end. In practice a handful do (most candidates are alone).
struct Propose {
  const Candidate* candidates;
  const std::uint32_t* index;  // rank -> candidate
  const std::uint32_t* remaining;
  std::uint32_t* best;  // per particle: the smallest rank proposed, kNoCandidate between rounds
  PARTICLE_HD void operator()(std::uint32_t k) const {
    const std::uint32_t rank = remaining[k];
    const Candidate& c = candidates[index[rank]];
    store_min(&best[c.i], rank);
    if (!is_wall(c)) store_min(&best[c.j], rank);
  }
};

struct Decide {
  const Candidate* candidates;
  const std::uint32_t* index;
  const std::uint32_t* remaining;
  const std::uint32_t* best;
  std::uint8_t* taken;
  Candidate* accepted;
  std::uint32_t* accepted_size;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    const std::uint32_t rank = remaining[k];
    const Candidate& c = candidates[index[rank]];
    const bool wall = is_wall(c);
    if (best[c.i] != rank || (!wall && best[c.j] != rank)) return;
    taken[c.i] = 1;
    if (!wall) taken[c.j] = 1;
    accepted[claim(accepted_size)] = c;
  }
};

// Clears the proposals and keeps the candidates whose particles are both still free.
struct Sweep {
  const Candidate* candidates;
  const std::uint32_t* index;
  const std::uint32_t* remaining;
  std::uint32_t* best;
  const std::uint8_t* taken;
  std::uint32_t* next;
  std::uint32_t* next_size;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    const std::uint32_t rank = remaining[k];
    const Candidate& c = candidates[index[rank]];
    const bool wall = is_wall(c);
    best[c.i] = kNoCandidate;
    if (!wall) best[c.j] = kNoCandidate;
    if (!taken[c.i] && (wall || !taken[c.j])) next[claim(next_size)] = rank;
  }
};

}  // namespace particle::detail
