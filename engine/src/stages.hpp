#pragma once
// The sub-step pipeline's stages other than the broad phase. Functions marked "team" must be
// called by every thread of the enclosing OpenMP parallel region (they contain worksharing loops);
// the others run on one thread.
#include <cstdint>
#include <vector>

#include "world.hpp"

namespace particle::detail {

// team (a static split of the particles), no barrier: one wall candidate per particle that
// reaches a wall line.
void find_wall_candidates(const World& w, ThreadScratch& out);

// any thread: sorts by the total order (t, wall before pair, i, j).
void order_candidates(std::vector<Candidate>& candidates);

// one thread: splits the threads' candidates into the uncontested ones (their particles are in no
// other candidate, so the filter accepts them in any order) and the contested ones, ordered.
// `uses` is a per-particle scratch array, all zero on entry and on return.
void split_contested(const std::vector<ThreadScratch>& runs, std::vector<std::uint8_t>& uses,
                     std::vector<Candidate>& uncontested, std::vector<Candidate>& contested);

// one thread: greedy one-collision-per-particle filter over the ordered candidates.
// Marks taken[i] for every accepted particle; taken must be all zero on entry.
void filter_candidates(const std::vector<Candidate>& ordered, std::vector<std::uint8_t>& taken,
                       std::vector<Candidate>& accepted);

// one thread: appends the uncontested candidates to `accepted` and marks their particles taken.
void accept_uncontested(const std::vector<Candidate>& uncontested, std::vector<std::uint8_t>& taken,
                        std::vector<Candidate>& accepted);

// team, no barrier at the end: applies the accepted collisions (they share no particle).
void resolve_collisions(const World& w, const std::vector<Candidate>& accepted);

// team, barrier at the end: moves every particle without a collision by its full displacement
// and clears taken[] for the next sub-step.
void advance_free(const World& w, std::vector<std::uint8_t>& taken);

// Moves one coordinate by u * t and keeps it on the wall line if the move would cross it: the
// model's "stops just next to the wall"; only rounding reaches past a line otherwise.
inline double move_clamped(double x, double u, double t, double lo, double hi) {
  const double moved = x + u * t;
  return moved < lo ? lo : (moved > hi ? hi : moved);
}

}  // namespace particle::detail
