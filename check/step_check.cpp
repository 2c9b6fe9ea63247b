#include "step_check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "model.hpp"
#include "particle/random_scene.hpp"
#include "tolerance.hpp"

namespace particle::check {

namespace {

// A start within the print rounding of `start`, positions kept in the box (the program's were).
Particles perturbed(const Scene& scene, const Particles& start, std::uint64_t seed, bool corners) {
  Random random(seed);
  Particles p = start;
  const auto move = [&](double& v) {
    const double u = random.uniform();
    v += kPrintRounding * (corners ? (u < 0.5 ? -1.0 : 1.0) : 2 * u - 1);
  };
  const double lo = scene.r, hi = scene.L - scene.r;
  for (std::size_t i = 0; i < p.size(); ++i) {
    move(p.x[i]);
    move(p.y[i]);
    move(p.vx[i]);
    move(p.vy[i]);
    p.x[i] = std::clamp(p.x[i], lo, hi);
    p.y[i] = std::clamp(p.y[i], lo, hi);
  }
  return p;
}

std::string collisions(const Particles& p, std::size_t i) {
  return fmt::format("{} pair, {} wall", p.pair_collisions[i], p.wall_collisions[i]);
}

}  // namespace

StepResult check_step(const Scene& scene, int slow_factor, std::int64_t step,
                      const Particles& start, bool exact_start, const Particles& printed) {
  StepResult result;
  result.model = model_step(scene, start, slow_factor);
  const Tolerance tolerance(scene, start, exact_start);
  std::vector<std::uint32_t> beyond;
  for (std::size_t i = 0; i < start.size(); ++i) {
    const double allowed = tolerance.of(start, result.model, i);
    result.largest_tolerance = std::max(result.largest_tolerance, allowed);
    const double d = difference(result.model, printed, i);
    if (d <= allowed) continue;
    beyond.push_back(static_cast<std::uint32_t>(i));
    result.largest_difference = std::max(result.largest_difference, d);
  }
  if (beyond.empty()) return result;
  std::vector<bool> explained(beyond.size(), false);
  // The first time unit starts from the scene's exact values: nothing to perturb.
  for (int draw = 0; draw < kDraws && !exact_start; ++draw) {
    const Particles moved =
        perturbed(scene, start, static_cast<std::uint64_t>(step) * kDraws + draw, draw % 2 == 1);
    const Particles model = model_step(scene, moved, slow_factor);
    const Tolerance around(scene, moved, false);
    bool all = true;
    for (std::size_t k = 0; k < beyond.size(); ++k) {
      const std::uint32_t i = beyond[k];
      if (!explained[k] && difference(model, printed, i) <= around.of(moved, model, i)) {
        explained[k] = true;
        if (result.detail.empty())
          result.detail = fmt::format(
              "particle {} is {:.3g} from the model run from the printed state ({} collisions); "
              "a start within the print rounding gives the printed value ({} collisions)",
              i, difference(result.model, printed, i), collisions(result.model, i),
              collisions(model, i));
      }
      all = all && explained[k];
    }
    if (all) break;
  }
  for (std::size_t k = 0; k < beyond.size(); ++k)
    (explained[k] ? result.explained : result.unexplained).push_back(beyond[k]);
  return result;
}

}  // namespace particle::check
