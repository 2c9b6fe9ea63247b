// Resolve: each accepted collision (contact.hpp, resolve_collision). O(accepted); accepted
// collisions share no particle, so they run in parallel in any split.
#include <algorithm>

#include "contact.hpp"
#include "step/stages.hpp"

namespace particle::detail {
namespace {

// Asks for the lines collision c will write (its particles' state and counters). Always inlined:
// GCC otherwise passed the pointers through memory for nothing but prefetches.
[[gnu::always_inline]] inline void prefetch_collision(const World& w, const Candidate& c) {
  for (const std::uint32_t i : {c.i, c.j}) {
    __builtin_prefetch(w.x + i, 1);
    __builtin_prefetch(w.y + i, 1);
    __builtin_prefetch(w.ux + i, 1);
    __builtin_prefetch(w.uy + i, 1);
    __builtin_prefetch(w.pair_collisions + i, 1);
    if (is_wall(c)) {
      __builtin_prefetch(w.wall_collisions + i, 1);
      __builtin_prefetch(w.wall_impulse + i, 1);
      break;
    }
  }
}

}  // namespace

std::uint64_t resolve_collisions(const World& w, const std::vector<Candidate>& accepted,
                                 std::size_t first, std::size_t last) {
  last = std::min(last, accepted.size());
  // The accepted collisions are spread over the whole state: on the million-particle scene,
  // about one particle in 33 a sub-step, each a miss in every array it writes. A state that
  // stays in cache (below kFarState particles) is not worth the prefetches' instructions.
  constexpr std::size_t kAhead = 8, kFarState = std::size_t{1} << 16;
  std::uint64_t stopped = 0;
  std::size_t k = first;
  if (w.n >= kFarState)
    for (; k + kAhead < last; ++k) {
      prefetch_collision(w, accepted[k + kAhead]);
      stopped += stopped_count(resolve_collision(w, accepted[k]));
    }
  for (; k < last; ++k) stopped += stopped_count(resolve_collision(w, accepted[k]));
  return stopped;
}

}  // namespace particle::detail
