#include "model.hpp"

#include <fmt/format.h>

namespace particle::check {

StageStep::StageStep(const Scene& scene, const Particles& start, const StepRules& rules)
    : scene_(scene), start_(start), rules_(rules) {}

Particles StageStep::run(const Alteration& alter, std::vector<SubStep>* record) const {
  return replay_time_unit(scene_, start_, rules_, alter, record);
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

const Candidate* collision_of(const std::vector<Candidate>& accepted, std::uint32_t i) {
  for (const Candidate& c : accepted)
    if (involves(c, i)) return &c;
  return nullptr;
}

Event StageStep::event(int k, const Candidate& c) const {
  Event e;
  e.time = (k + c.t) / rules_.slow_factor;
  e.i = c.i;
  e.wall = is_wall(c);
  e.j = e.wall ? c.i : c.j;
  e.flips_x = c.j == kWallX || c.j == kWallCorner;
  e.flips_y = c.j == kWallY || c.j == kWallCorner;
  e.overlap = !e.wall && c.t == 0;  // the model's t = 0 for a pair: overlapping and approaching
  return e;
}

}  // namespace particle::check
