// Order: sort candidates by the key (t, wall before pair, i, j). The key is a total order over
// distinct candidates, so the result does not depend on how threads or broad phases enumerated
// them. O(C log C) for C candidates per sub-step, a small fraction of N in practice.
#include <algorithm>
#include <tuple>

#include "stages.hpp"

namespace particle::detail {

void order_candidates(std::vector<Candidate>& candidates) {
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::make_tuple(a.t, !is_wall(a), a.i, a.j) <
           std::make_tuple(b.t, !is_wall(b), b.i, b.j);
  });
}

}  // namespace particle::detail
