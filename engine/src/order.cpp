// Order: sort candidates by the key (t, wall before pair, i, j). The key is a total order over
// distinct candidates, so the result does not depend on how threads or broad phases enumerated
// them. Each thread sorts its own buffer in parallel (O(C/T log C/T)); one thread then merges the
// T sorted runs (O(C log T)), which keeps the sequential part of a sub-step small.
#include <algorithm>

#include "stages.hpp"

namespace particle::detail {
namespace {

// A function object, not a function pointer, so that the sorts inline it.
struct Before {
  bool operator()(const Candidate& a, const Candidate& b) const {
    if (a.t != b.t) return a.t < b.t;
    const bool a_wall = is_wall(a), b_wall = is_wall(b);
    if (a_wall != b_wall) return a_wall;
    if (a.i != b.i) return a.i < b.i;
    return a.j < b.j;
  }
};

}  // namespace

void order_candidates(std::vector<Candidate>& candidates) {
  std::sort(candidates.begin(), candidates.end(), Before{});
}

void merge_ordered(const std::vector<ThreadScratch>& runs, std::vector<Candidate>& ordered,
                   std::vector<Candidate>& spare) {
  ordered.clear();
  for (const ThreadScratch& run : runs) {
    spare.resize(ordered.size() + run.candidates.size());
    std::merge(ordered.begin(), ordered.end(), run.candidates.begin(), run.candidates.end(),
               spare.begin(), Before{});
    ordered.swap(spare);
  }
}

}  // namespace particle::detail
