// Filter: walk the ordered candidates and accept one when none of its particles is taken yet, so
// each particle takes at most one collision per sub-step (ignored pairs pass through each other).
// O(C), sequential by nature: each decision depends on all earlier ones.
#include "step/stages.hpp"

namespace particle {

void filter_candidates(const std::vector<Candidate>& ordered, std::vector<std::uint8_t>& taken,
                       std::vector<Candidate>& accepted) {
  accepted.clear();
  for (const Candidate& c : ordered) {
    if (taken[c.i]) continue;
    if (is_wall(c)) {
      taken[c.i] = 1;
    } else {
      if (taken[c.j]) continue;
      taken[c.i] = taken[c.j] = 1;
    }
    accepted.push_back(c);
  }
}

namespace detail {

void accept_uncontested(const std::vector<Candidate>& uncontested, std::vector<std::uint8_t>& taken,
                        std::vector<Candidate>& accepted) {
  for (const Candidate& c : uncontested) {
    taken[c.i] = 1;
    if (!is_wall(c)) taken[c.j] = 1;
    accepted.push_back(c);
  }
}

void release_taken(const std::vector<Candidate>& accepted, std::vector<std::uint8_t>& taken) {
  for (const Candidate& c : accepted) {
    taken[c.i] = 0;
    if (!is_wall(c)) taken[c.j] = 0;
  }
}

}  // namespace detail
}  // namespace particle
