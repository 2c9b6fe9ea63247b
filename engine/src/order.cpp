// Order: sort candidates by the key (t, wall before pair, i, j). The key is a total order over
// distinct candidates, so the result does not depend on how threads or broad phases enumerated
// them.
//
// Only contested candidates need it: a candidate whose particles appear in no other candidate is
// accepted by the greedy filter wherever it stands in the order, so split_contested() sets those
// apart in O(C) (a use count per particle) and sorts the rest. In the default scene about nine in
// ten candidates are a lone wall hit, so the sort shrinks tenfold; the accepted set is the same.
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

void split_contested(std::span<const ThreadScratch> runs, std::vector<std::uint8_t>& uses,
                     std::vector<Candidate>& uncontested, std::vector<Candidate>& contested) {
  uncontested.clear();
  contested.clear();
  const auto count = [&](std::uint32_t i) {
    uses[i] = static_cast<std::uint8_t>(uses[i] < 2 ? uses[i] + 1 : 2);
  };
  for (const ThreadScratch& run : runs)
    for (const Candidate& c : run.candidates) {
      count(c.i);
      if (!is_wall(c)) count(c.j);
    }
  for (const ThreadScratch& run : runs)
    for (const Candidate& c : run.candidates) {
      const bool alone = uses[c.i] == 1 && (is_wall(c) || uses[c.j] == 1);
      (alone ? uncontested : contested).push_back(c);
    }
  for (const ThreadScratch& run : runs)
    for (const Candidate& c : run.candidates) {
      uses[c.i] = 0;
      if (!is_wall(c)) uses[c.j] = 0;
    }
  order_candidates(contested);
}

}  // namespace particle::detail
