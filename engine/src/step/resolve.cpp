// Resolve: each accepted collision (contact.hpp, resolve_collision). O(accepted); accepted
// collisions share no particle, so they run in parallel in any split.
#include <algorithm>

#include "contact.hpp"
#include "step/stages.hpp"

namespace particle::detail {

std::uint64_t resolve_collisions(const World& w, const std::vector<Candidate>& accepted,
                                 std::size_t first, std::size_t last) {
  last = std::min(last, accepted.size());
  std::uint64_t stopped = 0;
  for (std::size_t k = first; k < last; ++k)
    stopped += stopped_count(resolve_collision(w, accepted[k]));
  return stopped;
}

}  // namespace particle::detail
