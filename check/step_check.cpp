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

// Why two starts within the print rounding of each other give particle i two outcomes: the
// first sub-step where its collision differs between them, both events with their times, and
// what lets the rounding swap them (a near-tie, a contact at the step's end, a graze).
std::string competing(const Scene& scene, const StepRules& rules, const Particles& start,
                      const Particles& moved, std::uint32_t i) {
  const StageStep from_printed(scene, start, rules), from_moved(scene, moved, rules);
  std::vector<SubStep> a, b;
  from_printed.run({}, &a);
  from_moved.run({}, &b);
  for (int k = 0; k < static_cast<int>(a.size()); ++k) {
    const Candidate* x = collision_of(a[k].accepted, i);
    const Candidate* y = collision_of(b[k].accepted, i);
    if (!x && !y) continue;
    if (x && y && x->i == y->i && x->j == y->j) continue;
    const std::string model = x ? "the " + describe(from_printed.event(k, *x)) : "no collision";
    const std::string other = y ? "the " + describe(from_moved.event(k, *y)) : "no collision";
    std::string why;
    if (x && y && is_wall(*x) && is_wall(*y)) {
      why =
          "a corner: both wall lines at the same time from the printed state, one first from a "
          "start within the rounding";
    } else if (x && y) {
      const double apart = std::fabs(from_printed.event(k, *x).time - from_moved.event(k, *y).time);
      why = apart > 0 ? fmt::format("a near-tie: {:.3g} of a step apart", apart)
                      : "a tie: both at the same time, broken the other way from a start within "
                        "the rounding";
    } else {
      const Event e = x ? from_printed.event(k, *x) : from_moved.event(k, *y);
      why = 1 - e.time < 1e-6 ? "a contact at the step's end"
                              : "a graze: the contact is within the rounding of a miss";
    }
    return fmt::format(
        "the model run from the printed state takes {}; a start within the print rounding "
        "takes {} ({}) and gives the printed value",
        model, other, why);
  }
  // The same collisions from both starts: one of them magnifies the start's difference.
  for (int k = 0; k < static_cast<int>(a.size()); ++k)
    if (const Candidate* x = collision_of(a[k].accepted, i))
      return fmt::format(
          "the same collisions from both starts, but the {} magnifies a difference within the "
          "print rounding (a grazing contact) to the printed value",
          describe(from_printed.event(k, *x)));
  return "a start within the print rounding gives the printed value";
}

// The model with its contacts at exactly the time unit's end (t = 1 of the last sub-step) taken
// at the start of the next time unit instead (docs/model.md, "Readings of the specification"):
// the specification's "at any time during a step" leaves the step's end to either step, and both
// public student programs tried take it in the next (the 2019 authors' in this one). Such a contact
// is the last in the order, so leaving it out changes nothing the filter decided before it; the
// next time unit, run from this state, takes it at t = 0. `deferred`: the collisions left out.
Particles end_contacts_deferred(const Scene& scene, const StepRules& rules, const Particles& start,
                                std::vector<Event>& deferred) {
  const StageStep from_start(scene, start, rules);
  const int last = rules.slow_factor - 1;
  return from_start.run(
      [&](int k, const std::vector<Candidate>&, std::vector<Candidate>& accepted) {
        if (k != last) return;
        std::erase_if(accepted, [&](const Candidate& c) {
          if (c.t != 1) return false;
          deferred.push_back(from_start.event(k, c));
          return true;
        });
      });
}

// Whether the model can hold a contact at exactly the step's end for one of `beyond`: it sits on a
// wall line (a wall hit at t = 1 leaves it there: lengths are scaled by powers of two, so exactly)
// or touches another particle (a pair at t = 1 ends at the contact distance). O(beyond x N), so
// that the O(N^2) replay of end_contacts_deferred runs only where it may explain something.
bool may_touch_at_end(const Scene& scene, const Particles& model,
                      const std::vector<std::uint32_t>& beyond) {
  const double lo = scene.r, hi = scene.L - scene.r, reach = 4 * scene.r * scene.r * (1 + 1e-6);
  for (const std::uint32_t i : beyond) {
    if (model.x[i] == lo || model.x[i] == hi || model.y[i] == lo || model.y[i] == hi) return true;
    for (std::size_t j = 0; j < model.size(); ++j) {
      const double dx = model.x[j] - model.x[i], dy = model.y[j] - model.y[i];
      if (j != i && dx * dx + dy * dy <= reach) return true;
    }
  }
  return false;
}

}  // namespace

StepResult check_step(const Scene& scene, const StepRules& rules, std::int64_t step,
                      const Particles& start, bool exact_start, const Particles& printed,
                      const Particles& model) {
  StepResult result;
  result.model = model;
  const Tolerance tolerance(scene, start, exact_start, rules.wall_stop);
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
  std::vector<Event> deferred;
  const Particles later = may_touch_at_end(scene, result.model, beyond)
                              ? end_contacts_deferred(scene, rules, start, deferred)
                              : Particles();
  for (std::size_t k = 0; k < beyond.size() && !deferred.empty(); ++k) {
    const std::uint32_t i = beyond[k];
    if (difference(later, printed, i) > tolerance.of(start, later, i)) continue;
    explained[k] = true;
    if (result.detail.empty())
      for (const Event& e : deferred)
        if (e.i == i || e.j == i)
          result.detail = fmt::format(
              "the model takes the {} in this step; the program takes it at the start of the "
              "next: a contact at exactly the step's end, which the specification leaves to "
              "either step (docs/model.md)",
              describe(e));
  }
  // The first time unit starts from the scene's exact values: nothing to perturb.
  for (int draw = 0; draw < kDraws && !exact_start &&
                     !std::all_of(explained.begin(), explained.end(), [](bool e) { return e; });
       ++draw) {
    const Particles moved =
        perturbed(scene, start, static_cast<std::uint64_t>(step) * kDraws + draw, draw % 2 == 1);
    const Particles model = step_time_unit(scene, moved, rules);
    const Tolerance around(scene, moved, false, rules.wall_stop);
    bool all = true;
    for (std::size_t k = 0; k < beyond.size(); ++k) {
      const std::uint32_t i = beyond[k];
      if (!explained[k] && difference(model, printed, i) <= around.of(moved, model, i)) {
        explained[k] = true;
        if (result.detail.empty()) result.detail = competing(scene, rules, start, moved, i);
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
