// Order: sort candidates by the key (t, wall before pair, i, j). The key is a total order over
// distinct candidates, so the result does not depend on how threads or broad phases enumerated
// them.
//
// Only contested candidates need it: a candidate whose particles appear in no other candidate is
// accepted by the greedy filter wherever it stands in the order, so split_contested() sets those
// apart in O(C) (a use count per particle) and sorts the rest. In the default scene about nine in
// ten candidates are a lone wall hit, so the sort shrinks tenfold; the accepted set is the same.
#include <algorithm>

#include "step/stages.hpp"

namespace particle::detail {
namespace {

// A function object, not a function pointer, so that the sorts inline it. Compares the
// particles' ids, not their slots, so that a run in cell order sorts as one in id order.
struct Before {
  const std::uint32_t* id;
  bool operator()(const Candidate& a, const Candidate& b) const {
    if (a.t != b.t) return a.t < b.t;
    const bool a_wall = is_wall(a), b_wall = is_wall(b);
    if (a_wall != b_wall) return a_wall;
    const std::uint32_t ai = particle_id(id, a.i), bi = particle_id(id, b.i);
    if (ai != bi) return ai < bi;
    return a_wall ? a.j < b.j : particle_id(id, a.j) < particle_id(id, b.j);
  }
};

}  // namespace

Candidate oriented(Candidate c, const std::uint32_t* id) {
  if (id && !is_wall(c) && id[c.i] > id[c.j]) std::swap(c.i, c.j);
  return c;
}

void order_candidates(std::vector<Candidate>& candidates, const std::uint32_t* id) {
  std::sort(candidates.begin(), candidates.end(), Before{id});
}

void split_contested(std::span<const ThreadScratch> runs, bool with_receding,
                     std::vector<std::uint8_t>& uses, std::vector<Candidate>& uncontested,
                     std::vector<Candidate>& contested, const std::uint32_t* id,
                     std::size_t complete) {
  uncontested.clear();
  contested.clear();
  const auto each_candidate = [&](auto&& visit) {
    for (const ThreadScratch& run : runs) {
      for (const Candidate& c : run.candidates) visit(c);
      if (with_receding)
        for (const Candidate& c : run.receding) visit(c);
    }
  };
  const auto count = [&](std::uint32_t i) {
    uses[i] = static_cast<std::uint8_t>(uses[i] < 2 ? uses[i] + 1 : 2);
  };
  each_candidate([&](const Candidate& c) {
    count(c.i);
    if (!is_wall(c)) count(c.j);
  });
  each_candidate([&](const Candidate& c) {
    const bool alone =
        uses[c.i] == 1 && c.i < complete && (is_wall(c) || (uses[c.j] == 1 && c.j < complete));
    if (alone)
      uncontested.push_back(c);
    else
      contested.push_back(oriented(c, id));
  });
  each_candidate([&](const Candidate& c) {
    uses[c.i] = 0;
    if (!is_wall(c)) uses[c.j] = 0;
  });
  order_candidates(contested, id);
}

}  // namespace particle::detail
