// Order: sort candidates by the key (t, wall before pair, i, j). The key is a total order over
// distinct candidates, so the result does not depend on how threads or broad phases enumerated
// them.
//
// Only contested candidates need it: a candidate whose particles appear in no other candidate is
// accepted by the greedy filter wherever it stands in the order, so split_contested() sets those
// apart in O(C) (a use count per particle) and sorts the rest. In the default scene about nine in
// ten candidates are a lone wall hit, so the sort shrinks tenfold; the accepted set is the same.
#include <algorithm>

#include "parallel/team.hpp"
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

namespace {

template <class Visit>
void each_candidate(const ThreadScratch& run, bool with_receding, Visit&& visit) {
  for (const Candidate& c : run.candidates) visit(c);
  if (with_receding)
    for (const Candidate& c : run.receding) visit(c);
}

template <class Visit>
void each_particle(const Candidate& c, Visit&& visit) {
  visit(c.i);
  if (!is_wall(c)) visit(c.j);
}

// Counts each particle's candidates in `uses`, up to 2.
void count_uses(const ThreadScratch& run, bool with_receding, std::vector<std::uint8_t>& uses) {
  each_candidate(run, with_receding, [&](const Candidate& c) {
    each_particle(c, [&](std::uint32_t i) {
      uses[i] = static_cast<std::uint8_t>(uses[i] < 2 ? uses[i] + 1 : 2);
    });
  });
}

void clear_uses(const ThreadScratch& run, bool with_receding, std::vector<std::uint8_t>& uses) {
  each_candidate(run, with_receding, [&](const Candidate& c) {
    each_particle(c, [&](std::uint32_t i) { uses[i] = 0; });
  });
}

// The split itself; alone(i): particle i is in this candidate alone.
template <class Alone>
void split_run(const ThreadScratch& run, bool with_receding, Alone&& alone,
               std::vector<Candidate>& uncontested, std::vector<Candidate>& contested,
               const std::uint32_t* id, std::size_t complete) {
  each_candidate(run, with_receding, [&](const Candidate& c) {
    if (alone(c.i) && c.i < complete && (is_wall(c) || (alone(c.j) && c.j < complete)))
      uncontested.push_back(c);
    else
      contested.push_back(oriented(c, id));
  });
}

}  // namespace

void split_contested(std::span<const ThreadScratch> runs, bool with_receding,
                     std::vector<std::uint8_t>& uses, std::vector<Candidate>& uncontested,
                     std::vector<Candidate>& contested, const std::uint32_t* id,
                     std::size_t complete) {
  uncontested.clear();
  contested.clear();
  for (const ThreadScratch& run : runs) count_uses(run, with_receding, uses);
  const auto alone = [&](std::uint32_t i) { return uses[i] == 1; };
  for (const ThreadScratch& run : runs)
    split_run(run, with_receding, alone, uncontested, contested, id, complete);
  for (const ThreadScratch& run : runs) clear_uses(run, with_receding, uses);
  order_candidates(contested, id);
}

void split_own_contested(std::span<const ThreadScratch> runs, std::span<Selection> selections,
                         int t, bool with_receding, const std::uint32_t* id) {
  const auto own = static_cast<std::size_t>(t);
  Selection& mine = selections[own];
  mine.uncontested.clear();
  mine.contested.clear();
  count_uses(runs[own], with_receding, mine.uses);
  team_barrier();  // every thread's candidates counted
  // In one candidate alone: in one of this thread's and in none of the others'.
  const auto alone = [&](std::uint32_t i) {
    if (mine.uses[i] != 1) return false;
    for (std::size_t k = 0; k < selections.size(); ++k)
      if (k != own && selections[k].uses[i] != 0) return false;
    return true;
  };
  split_run(runs[own], with_receding, alone, mine.uncontested, mine.contested, id, SIZE_MAX);
  team_barrier();  // no thread reads the counts any more
  clear_uses(runs[own], with_receding, mine.uses);
}

}  // namespace particle::detail
