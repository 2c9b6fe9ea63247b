// particle/replay.hpp. The replay is simulate()'s own set-up and conversion back (simulate_with)
// with the stages run here one by one, on all pairs, in place of an engine.
#include "particle/replay.hpp"

#include <algorithm>

#include "broad_phase/brute.hpp"
#include "engines.hpp"
#include "particle/simulation.hpp"
#include "step/stages.hpp"

namespace particle {

namespace {

// One time unit of `scene` from `start`, its collision counts zero.
Scene one_time_unit(const Scene& scene, const Particles& start) {
  Scene one;
  one.L = scene.L;
  one.r = scene.r;
  one.steps = 1;
  one.mode = scene.mode;
  one.particles = start;
  std::fill(one.particles.pair_collisions.begin(), one.particles.pair_collisions.end(), 0);
  std::fill(one.particles.wall_collisions.begin(), one.particles.wall_collisions.end(), 0);
  return one;
}

// The K sub-steps on `w`, in the engine's length unit.
void stages(const detail::World& w, int slow_factor, const Alteration& alter,
            std::vector<SubStep>* record) {
  detail::BruteBroadPhase brute;
  std::vector<std::uint8_t> taken(w.n, 0);
  for (int k = 0; k < slow_factor; ++k) {
    detail::ThreadScratch found;
    for (std::size_t c = 0; c < (w.n + detail::kWallChunk - 1) / detail::kWallChunk; ++c)
      detail::find_wall_candidates_in(w, c, found);
    for (std::uint32_t c = 0; c < brute.chunks(w); ++c) brute.find_pairs_in(w, c, found);
    SubStep sub;
    sub.ordered = std::move(found.candidates);
    if (w.overlaps_collide)  // as split_contested takes them
      sub.ordered.insert(sub.ordered.end(), found.receding.begin(), found.receding.end());
    detail::order_candidates(sub.ordered);
    filter_candidates(sub.ordered, taken, sub.accepted);
    if (alter) {
      alter(k, sub.ordered, sub.accepted);
      std::fill(taken.begin(), taken.end(), 0);
      for (const Candidate& c : sub.accepted) {
        taken[c.i] = 1;
        if (!is_wall(c)) taken[c.j] = 1;
      }
    }
    detail::resolve_collisions(w, sub.accepted);
    detail::advance_free(w, taken);
    std::fill(taken.begin(), taken.end(), 0);
    if (record) record->push_back(std::move(sub));
  }
}

RunOptions one_thread(const StepRules& rules) {
  RunOptions options;
  options.threads = 1;
  options.slow_factor = rules.slow_factor;
  options.wall_stop = rules.wall_stop;
  options.overlap = rules.overlap;
  return options;
}

}  // namespace

Particles step_time_unit(const Scene& scene, const Particles& start, const StepRules& rules) {
  Scene one = one_time_unit(scene, start);
  simulate(one, one_thread(rules));
  return std::move(one.particles);
}

Particles replay_time_unit(const Scene& scene, const Particles& start, const StepRules& rules,
                           const Alteration& alter, std::vector<SubStep>* record) {
  Scene one = one_time_unit(scene, start);
  detail::simulate_with(
      one, one_thread(rules), {},
      [&](const detail::World& w, const RunOptions&, const detail::PipelineParams&) {
        stages(w, rules.slow_factor, alter, record);
        return RunReport{};
      });
  return std::move(one.particles);
}

}  // namespace particle
