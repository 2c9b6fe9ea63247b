#include "model.hpp"

#include <fmt/format.h>

namespace particle::check {

StageStep::StageStep(const Scene& scene, const Particles& start, const StepRules& rules)
    : scene_(scene), start_(start), rules_(rules) {}

Particles StageStep::run(const Alteration& alter, std::vector<SubStep>* record) const {
  return replay_time_unit(scene_, start_, rules_, alter, record);
}

namespace {

// Six digits, unless they round a time inside the step to its start or end: a hit 1e-15 before
// the end is not one at t = 1, which the specification leaves to either step (docs/model.md).
std::string time_text(double t) {
  const std::string text = fmt::format("{:.6g}", t);
  return (text == "0" || text == "1") && t != 0 && t != 1 ? fmt::format("{:.17g}", t) : text;
}

}  // namespace

std::string describe(const Event& e) {
  if (e.wall)
    return fmt::format("wall hit of particle {} at t = {} of the step ({} flip{})", e.i,
                       time_text(e.time),
                       e.flips_x && e.flips_y ? "vx and vy" : (e.flips_x ? "vx" : "vy"),
                       e.flips_x && e.flips_y ? "" : "s");
  if (e.overlap)
    return fmt::format("overlapping approaching pair {}-{} (collides at t = {})", e.i, e.j,
                       time_text(e.time));
  return fmt::format("pair {}-{} at t = {} of the step", e.i, e.j, time_text(e.time));
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
