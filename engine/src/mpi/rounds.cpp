// The filter in rounds across ranks (mpi/rounds.hpp): step/filter_rounds.hpp's stages, one index
// at a time on this rank's main thread, with the halo's forwards between them.
#include "mpi/rounds.hpp"

#include <numeric>
#include <stdexcept>
#include <string>

#include "step/filter_rounds.hpp"

namespace particle::detail::mpi {
namespace {

Proposal proposal_of(const World& w, const Candidate& c) {
  return {w.id[c.i], is_wall(c) ? c.j : w.id[c.j]};
}

// Each halo particle's proposal made here stands only where it is the owner's.
void take_owners_proposals(const std::vector<Candidate>& ordered, const World& w, const Halo& halo,
                           std::vector<std::uint32_t>& best, std::vector<Proposal>& proposals) {
  halo.forward_of(
      [&](std::uint32_t slot) {
        return best[slot] == kNoCandidate ? Proposal{} : proposal_of(w, ordered[best[slot]]);
      },
      proposals.data());
  for (std::size_t slot = halo.owned(); slot < w.n; ++slot)
    if (best[slot] != kNoCandidate && proposal_of(w, ordered[best[slot]]) != proposals[slot])
      best[slot] = kNoCandidate;
}

}  // namespace

void accept_in_rounds(const std::vector<Candidate>& ordered, const World& w, const Halo& halo,
                      RoundsScratch& s, std::vector<std::uint8_t>& taken,
                      std::vector<Candidate>& accepted) {
  const auto count = static_cast<std::uint32_t>(ordered.size());
  if (s.best.size() < w.n) s.best.resize(w.n, kNoCandidate);  // kNoCandidate between calls
  s.index.resize(count);
  std::iota(s.index.begin(), s.index.end(), 0u);  // ordered already: rank k is candidate k
  s.remaining = s.index;
  s.next.resize(count);
  accepted.resize(count);
  s.proposals.resize(w.n);
  std::uint32_t accepted_size = 0;
  for (std::uint64_t everywhere = sum_over_ranks(s.remaining.size()); everywhere > 0;) {
    ++tally().filter_rounds;
    const auto left = static_cast<std::uint32_t>(s.remaining.size());
    const Candidate* c = ordered.data();
    const std::uint32_t* index = s.index.data();
    const std::uint32_t* remaining = s.remaining.data();
    for (std::uint32_t k = 0; k < left; ++k) Propose{c, index, remaining, s.best.data()}(k);
    take_owners_proposals(ordered, w, halo, s.best, s.proposals);
    for (std::uint32_t k = 0; k < left; ++k)
      Decide{c, index, remaining, s.best.data(), taken.data(), accepted.data(), &accepted_size}(k);
    halo.forward(taken.data());
    std::uint32_t next_size = 0;
    for (std::uint32_t k = 0; k < left; ++k)
      Sweep{c, index, remaining, s.best.data(), taken.data(), s.next.data(), &next_size}(k);
    s.next.resize(next_size);
    std::swap(s.remaining, s.next);
    s.next.resize(count);
    // Each round accepts at least the first remaining candidate (mpi/rounds.hpp): one that does
    // not is a bug (ranks that disagree on a candidate), and looping on it would hang every rank.
    // The sum is the same on every rank, so all of them stop here alike.
    const std::uint64_t now = sum_over_ranks(s.remaining.size());
    if (now >= everywhere)
      throw std::logic_error("MPI filter: a round accepted nothing (" + std::to_string(everywhere) +
                             " candidates left over all ranks)");
    everywhere = now;
  }
  accepted.resize(accepted_size);
  // Back to kNoCandidate where the rounds wrote: O(candidates), not a pass over every slot.
  for (const Candidate& c : ordered) {
    s.best[c.i] = kNoCandidate;
    if (!is_wall(c)) s.best[c.j] = kNoCandidate;
  }
}

}  // namespace particle::detail::mpi
