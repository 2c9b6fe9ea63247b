#pragma once
// The sub-step pipeline's stages other than the broad phase. Functions marked "team" must be
// called by every thread of the enclosing OpenMP parallel region (they contain worksharing loops);
// the others run on any one thread, on data that thread owns.
#include <cstdint>
#include <span>
#include <vector>

#include "world.hpp"

namespace particle::detail {

// team (dynamic chunks of kWallChunk particles, so a late thread leaves its share to the others),
// no barrier: one wall candidate per particle that reaches a wall line.
inline constexpr std::size_t kWallChunk = 512;
void find_wall_candidates(const World& w, ThreadScratch& out);
// any thread: the same for chunk c alone (particles [c kWallChunk, (c + 1) kWallChunk)).
void find_wall_candidates_in(const World& w, std::size_t c, ThreadScratch& out);
// any thread: the same for particle i alone (a broad phase that knows which can reach a wall
// line: broad_phase/cells.hpp).
void find_wall_candidate(const World& w, std::uint32_t i, ThreadScratch& out);

// any thread: sorts by the total order (t, wall before pair, i, j), i and j the particles' ids
// (id: the World's slot-to-particle map, nullptr for the identity).
void order_candidates(std::vector<Candidate>& candidates, const std::uint32_t* id = nullptr);

// any thread: the candidate with a pair's particles in the order of their ids (id: as above): the
// narrow phase orders a pair by slot, and the order must see the pair an id-ordered run would.
Candidate oriented(Candidate c, const std::uint32_t* id);

// one thread: splits the threads' candidates into the uncontested ones (their particles are in no
// other candidate, so the filter accepts them in any order) and the contested ones, ordered.
// `uses` is a per-particle scratch array, all zero on entry and on return. With a slot-to-particle
// map `id` (World::id), each contested pair comes out oriented(): i holds the particle with the
// smaller id, for the order's key. The uncontested stay as the narrow phase named them:
// resolve_collision gives the same state bit for bit either way (swapping a pair negates its
// differences exactly), and looking their ids up was half of this function's time on the
// million-particle scene.
// Only a particle in a slot below `complete` has all its candidates in `runs` (the mpi engine's
// own particles; a halo copy's others are on its owner), so only those can be uncontested.
// with_receding (the overlap reading `always`, World::overlaps_collide): the runs' receding
// overlapping pairs are candidates too.
void split_contested(std::span<const ThreadScratch> runs, bool with_receding,
                     std::vector<std::uint8_t>& uses, std::vector<Candidate>& uncontested,
                     std::vector<Candidate>& contested, const std::uint32_t* id = nullptr,
                     std::size_t complete = SIZE_MAX);

// one thread: the filter itself is particle::filter_candidates (particle/replay.hpp).

// one thread: appends the uncontested candidates to `accepted` and marks their particles taken.
void accept_uncontested(const std::vector<Candidate>& uncontested, std::vector<std::uint8_t>& taken,
                        std::vector<Candidate>& accepted);

// one thread: clears the taken[] marks of the accepted collisions, O(accepted), for the next
// sub-step (the filter's precondition).
void release_taken(const std::vector<Candidate>& accepted, std::vector<std::uint8_t>& taken);

// One thread's working memory for selecting the sub-step's collisions (split, order, filter).
// Every thread selects redundantly from the same candidates and gets the same result: a few
// microseconds of duplicated work instead of one thread selecting while the others wait at two
// more barriers (and stall whenever that one thread is descheduled). Where a sub-step has many
// candidates the shared state's team splits them instead (split_own_contested below;
// step/pipeline.hpp, kTeamSplitFrom).
// Line-aligned: side by side in a vector, one thread's vectors and the next one's shared a cache
// line, and every push_back of either moved it between the cores.
struct alignas(64) Selection {
  std::vector<std::uint8_t> uses, taken;  // per particle; all zero between sub-steps
  std::vector<Candidate> uncontested, contested, accepted;
};

// team, barriers inside: split_contested over the team, thread t of its own candidates runs[t]
// into selections[t]'s lists (the contested unordered), counting in selections[t].uses (all
// zero on entry and on return) and reading the others' counts. Thread t's uncontested are its
// own to accept: their particles are in no other candidate, of any thread.
void split_own_contested(std::span<const ThreadScratch> runs, std::span<Selection> selections,
                         int t, bool with_receding, const std::uint32_t* id);

// any thread: applies accepted[first, last) (accepted collisions share no particle, so any split
// between threads gives the same state). Returns how many of their particles a wall line stopped
// (ThreadScratch::wall_stops).
std::uint64_t resolve_collisions(const World& w, const std::vector<Candidate>& accepted,
                                 std::size_t first = 0, std::size_t last = SIZE_MAX);

// any thread: moves every particle of [first, last) without a collision (taken[i] == 0) by its
// full displacement. `owned`: no other thread reads or writes w meanwhile (a private copy, or a
// team of one), so a group of particles may be stored whole, a taken one's values as they were.
void advance_free(const World& w, const std::vector<std::uint8_t>& taken, std::size_t first = 0,
                  std::size_t last = SIZE_MAX, bool owned = false);

}  // namespace particle::detail
