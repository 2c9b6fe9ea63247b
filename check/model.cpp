#include "model.hpp"

#include <fmt/format.h>

#include <cmath>

#include "broad_phase/brute.hpp"
#include "engines.hpp"
#include "particle/simulation.hpp"
#include "step/stages.hpp"

namespace particle::check {

namespace {

// One time unit of `scene` from `start`, its collision counts zero: what a step's replay runs.
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

RunOptions one_thread(int slow_factor) {
  RunOptions options;
  options.threads = 1;
  options.slow_factor = slow_factor;
  return options;
}

}  // namespace

Particles model_step(const Scene& scene, const Particles& start, int slow_factor) {
  Scene one = one_time_unit(scene, start);
  simulate(one, one_thread(slow_factor));
  return std::move(one.particles);
}

StageStep::StageStep(const Scene& scene, const Particles& start, int slow_factor)
    : scene_(scene), start_(start), slow_factor_(slow_factor) {}

Particles StageStep::run(const Alteration& alter, std::vector<SubStep>* record) const {
  // simulate()'s own set-up and conversion back (simulate_with), with the stages run here one by
  // one in place of an engine.
  Scene one = one_time_unit(scene_, start_);
  detail::simulate_with(
      one, one_thread(slow_factor_), {},
      [&](const detail::World& w, const RunOptions&, const detail::PipelineParams&) {
        stages(w, alter, record);
        return RunReport{};
      });
  return std::move(one.particles);
}

void StageStep::stages(const detail::World& w, const Alteration& alter,
                       std::vector<SubStep>* record) const {
  const std::size_t n = w.n;
  detail::BruteBroadPhase brute;
  std::vector<std::uint8_t> taken(n, 0);
  for (int k = 0; k < slow_factor_; ++k) {
    detail::ThreadScratch found;
    for (std::size_t c = 0; c < (n + detail::kWallChunk - 1) / detail::kWallChunk; ++c)
      detail::find_wall_candidates_in(w, c, found);
    for (std::uint32_t c = 0; c < brute.chunks(w); ++c) brute.find_pairs_in(w, c, found);
    SubStep sub;
    sub.ordered = std::move(found.candidates);
    detail::order_candidates(sub.ordered);
    detail::filter_candidates(sub.ordered, taken, sub.accepted);
    if (alter) {
      alter(k, sub.ordered, sub.accepted);
      std::fill(taken.begin(), taken.end(), 0);
      for (const detail::Candidate& c : sub.accepted) {
        taken[c.i] = 1;
        if (!detail::is_wall(c)) taken[c.j] = 1;
      }
    }
    detail::resolve_collisions(w, sub.accepted);
    detail::advance_free(w, taken);
    std::fill(taken.begin(), taken.end(), 0);
    if (record) record->push_back(std::move(sub));
  }
}

std::string describe(const Event& e) {
  if (e.wall)
    return fmt::format("wall hit of particle {} at t = {:.6g} of the step ({} flip{})", e.i, e.time,
                       e.flips_x && e.flips_y ? "vx and vy" : (e.flips_x ? "vx" : "vy"),
                       e.flips_x && e.flips_y ? "" : "s");
  if (e.overlap)
    return fmt::format("overlapping approaching pair {}-{} (collides at t = {:.6g})", e.i, e.j,
                       e.time);
  return fmt::format("pair {}-{} at t = {:.6g} of the step", e.i, e.j, e.time);
}

const detail::Candidate* collision_of(const std::vector<detail::Candidate>& accepted,
                                      std::uint32_t i) {
  for (const detail::Candidate& c : accepted)
    if (c.i == i || (!detail::is_wall(c) && c.j == i)) return &c;
  return nullptr;
}

Event StageStep::event(int k, const detail::Candidate& c) const {
  Event e;
  e.time = (k + c.t) / slow_factor_;
  e.i = c.i;
  e.wall = detail::is_wall(c);
  e.j = e.wall ? c.i : c.j;
  e.flips_x = c.j == detail::kWallX || c.j == detail::kWallCorner;
  e.flips_y = c.j == detail::kWallY || c.j == detail::kWallCorner;
  e.overlap = !e.wall && c.t == 0;  // the model's t = 0 for a pair: overlapping and approaching
  return e;
}

}  // namespace particle::check
