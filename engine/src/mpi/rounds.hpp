#pragma once
// The one-collision-per-particle filter across ranks: the greedy in rounds of
// step/filter_rounds.hpp, on each rank over the candidates of its own particles, with a halo
// particle's proposal taken from its owner. It accepts exactly what the sequential filter accepts
// over the run's whole order (the proof is at Propose), because every rank sees, in each round,
// what a single filter over all candidates would:
//  - an own particle's candidates are all here (the halo holds every partner within reach), so
//    its proposal, the first of its remaining candidates, is the one of the whole order;
//  - a halo particle's proposal is its owner's, forwarded by the halo: a candidate here that is
//    not that proposal is not the first of its remaining ones elsewhere, and is not accepted;
//  - a candidate between two ranks is on both, with the same time (pair_terms is symmetric in
//    i and j), the same ids and the same two proposals, so both decide alike; which particles
//    were taken is forwarded too, so both drop alike.
// Each round accepts at least the first remaining candidate of the whole order, so the rounds
// end; every rank goes on until none is left on any (a sum over ranks per round).
//
// Cost per round: the stages over the remaining candidates, and two forwards of the halo (8 bytes
// and 1 byte a copy).
#include <cstdint>
#include <vector>

#include "mpi/halo.hpp"
#include "step/filter_rounds.hpp"
#include "world.hpp"

namespace particle::detail::mpi {

// The filter's working memory, kept from sub-step to sub-step.
// A candidate named by its particles' ids (a wall's by its particle and kind): what two ranks can
// compare. {kNoCandidate, kNoCandidate}: no proposal.
struct Proposal {
  std::uint32_t i = kNoCandidate, j = kNoCandidate;
  bool operator==(const Proposal&) const = default;
};

// Kept from sub-step to sub-step: allocated afresh, the per-slot arrays cost the kernel's zeroing
// of their pages every sub-step (8 MB of proposals at N = 10^6), and cleared whole, a pass over
// every slot; `best` is kNoCandidate everywhere between calls, reset where a call wrote.
struct RoundsScratch {
  std::vector<std::uint32_t> best, index, remaining, next;
  std::vector<Proposal> proposals;
};

// collective: the accepted collisions among `ordered` (this rank's candidates in the total
// order, slots of w, which holds every own and halo slot), into `accepted`; taken[slot] set for
// every particle of an accepted collision, own or halo (taken has a zero per slot on entry).
void accept_in_rounds(const std::vector<Candidate>& ordered, const World& w, const Halo& halo,
                      RoundsScratch& scratch, std::vector<std::uint8_t>& taken,
                      std::vector<Candidate>& accepted);

}  // namespace particle::detail::mpi
