#include "model.hpp"

#include <fmt/format.h>

#include <cmath>

#include "broad_phase/brute.hpp"
#include "particle/simulation.hpp"
#include "scale.hpp"
#include "step/stages.hpp"

namespace particle::check {

Particles model_step(const Scene& scene, const Particles& start, int slow_factor) {
  Scene one;
  one.L = scene.L;
  one.r = scene.r;
  one.steps = 1;
  one.mode = scene.mode;
  one.particles = start;
  std::fill(one.particles.pair_collisions.begin(), one.particles.pair_collisions.end(), 0);
  std::fill(one.particles.wall_collisions.begin(), one.particles.wall_collisions.end(), 0);
  RunOptions options;
  options.threads = 1;
  options.slow_factor = slow_factor;
  simulate(one, options);
  return std::move(one.particles);
}

StageStep::StageStep(const Scene& scene, const Particles& start, int slow_factor)
    : scene_(scene), start_(start), slow_factor_(slow_factor) {}

Particles StageStep::run(const Alteration& alter, std::vector<SubStep>* record) const {
  // simulate()'s set-up: the engine's length unit and displacements per sub-step, both exact.
  Particles p = start_;
  const std::size_t n = p.size();
  std::fill(p.pair_collisions.begin(), p.pair_collisions.end(), 0);
  std::fill(p.wall_collisions.begin(), p.wall_collisions.end(), 0);
  const int unit = detail::length_exponent(scene_.L, scene_.contact_distance(),
                                           detail::speed_bound(p), slow_factor_);
  std::vector<double> ux, uy, impulse(n, 0.0);
  detail::to_displacements(p, unit, slow_factor_, ux, uy);
  detail::scale_lengths(p.x.data(), n, unit);
  detail::scale_lengths(p.y.data(), n, unit);
  const detail::World w = detail::make_world(
      std::ldexp(scene_.L, unit), std::ldexp(scene_.r, unit), n, p.x.data(), p.y.data(), ux.data(),
      uy.data(), p.pair_collisions.data(), p.wall_collisions.data(), impulse.data());
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
  const int k_log2 = std::ilogb(static_cast<double>(slow_factor_));
  detail::scale_lengths(p.x.data(), n, -unit);
  detail::scale_lengths(p.y.data(), n, -unit);
  detail::scale_lengths(ux.data(), p.vx.data(), n, k_log2 - unit);
  detail::scale_lengths(uy.data(), p.vy.data(), n, k_log2 - unit);
  return p;
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
