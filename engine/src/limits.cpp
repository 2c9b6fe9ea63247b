// The limits of a run that its header and options decide (particle/limits.hpp): one set of rules
// for the scene reader, psim and psweep.
#include "particle/limits.hpp"

#include <fmt/format.h>

#include <cmath>
#include <initializer_list>

#include "particle/random_scene.hpp"

namespace particle {

std::string particle_count_problem(std::int64_t n) {
  if (n >= 1 && n <= kMaxParticles) return "";
  return fmt::format("must be between 1 and {}, got {}", kMaxParticles, n);
}

std::string box_problem(double L) { return L > 0 ? "" : "must be positive"; }

std::string radius_problem(double L, double r) {
  if (!(r > 0)) return "must be positive";
  if (L < 2 * r) return "a particle of this radius does not fit in the box (L < 2r)";
  return "";
}

std::string steps_problem(std::int64_t steps) { return steps >= 0 ? "" : "must not be negative"; }

std::string default_speeds_problem(double L, double r) {
  if (std::isfinite(default_speed_range(L, r).max)) return "";
  return "the default speed range L/(8r) to L/4 is not finite; give a speed range";
}

namespace {

// Oler's inequality: points at mutual distance >= 1 in a convex region of area A and perimeter
// P number at most 2/sqrt(3) A + P/2 + 1. Centres lie in a square of side L - 2r at mutual
// distance >= 2r; in units of 2r, u = (L - 2r) / 2r gives 2/sqrt(3) u^2 + 2u + 1. The slack keeps
// rounding from refusing a count that fits exactly.
std::string packing_problem(std::int64_t n, double L, double r) {
  const double u = (L - 2 * r) / (2 * r);
  const double most = 2 / std::sqrt(3.0) * u * u + 2 * u + 1;
  if (static_cast<double>(n) <= most * (1 + 1e-9)) return "";
  return fmt::format(
      "scene too dense for random placement: {} disks of radius {:g} cannot be placed without "
      "overlap in a box of {:g} (at most {:.0f} fit); give fewer or smaller particles, or a "
      "larger box",
      n, r, L, std::floor(most));
}

}  // namespace

std::optional<LimitBreach> run_limit_breach(const RunRequest& run) {
  const auto first = [](std::initializer_list<LimitBreach> rules) -> std::optional<LimitBreach> {
    for (const LimitBreach& rule : rules)
      if (!rule.problem.empty()) return rule;
    return std::nullopt;
  };
  const SceneHeader& h = run.header;
  if (auto breach = first({{"N", particle_count_problem(h.n)},
                           {"L", box_problem(h.L)},
                           {"r", radius_problem(h.L, h.r)},
                           {"S", steps_problem(h.steps)}}))
    return breach;  // the rules below assume a valid header
  if (auto breach = option_breach(run.options)) return breach;
  return first({{"r", width_problem(h.L, h.r)},
                {"r", run.random && !run.speed ? default_speeds_problem(h.L, h.r) : ""},
                {"N", run.random ? packing_problem(h.n, h.L, h.r) : ""}});
}

}  // namespace particle
