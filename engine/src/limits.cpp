// The limits of a run that its header, options, seed and speeds or scene file decide
// (particle/limits.hpp): one set of rules for the scene reader, psim and psweep.
#include "particle/limits.hpp"

#include <fmt/format.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <tuple>

#include "particle/describe.hpp"
#include "particle/random_scene.hpp"
#include "scale.hpp"

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

// The chance that one draw of psim's placement lands within s = 2r of a disk already placed is
// at most the area so excluded over the area centres are drawn from, q = N pi s^2 / (L - 2r)^2.
// With q <= 1/2 a particle fails its kMaxPlacementAttempts (1000) draws with probability at most
// 2^-1000, so some particle of at most 10^8 fails with probability below 2^-973: over all seeds,
// placement does not fail.
bool placement_cannot_fail(std::int64_t n, double L, double r) {
  static_assert(kMaxPlacementAttempts >= 1000);
  const double span = L - 2 * r, s = 2 * r;
  return static_cast<double>(n) * std::numbers::pi * s * s <= 0.5 * span * span;
}

// What psim's draw of a random scene gives: the placement's problem ("" when all N are placed)
// and the speed bound of the velocities drawn.
struct Drawn {
  std::string placement;
  detail::SpeedBound speed;
};

// Draws the scene as psim would (place_random, the same seed and speeds) and remembers the last
// few thousand: a sweep checks the same scene under many other parameters. Bounded, so the
// expansion's memory stays constant; locked, so callers may be threads.
Drawn draw(const SceneHeader& h, std::uint64_t seed, SpeedRange speed) {
  using Key = std::tuple<std::int64_t, double, double, std::uint64_t, double, double>;
  static std::mutex lock;
  static std::map<Key, Drawn> drawn;
  const Key key{h.n, h.L, h.r, seed, speed.min, speed.max};
  {
    const std::lock_guard<std::mutex> hold(lock);
    if (const auto found = drawn.find(key); found != drawn.end()) return found->second;
  }
  Scene scene;
  scene.L = h.L;
  scene.r = h.r;
  scene.particles = Particles(static_cast<std::size_t>(h.n));
  Drawn result;
  try {
    place_random(scene, RandomInit{seed, speed});
    result.speed = detail::speed_bound(scene.particles);
  } catch (const InputError& e) {
    result.placement = e.what();
  }
  const std::lock_guard<std::mutex> hold(lock);
  if (drawn.size() >= 4096) drawn.clear();
  drawn.emplace(key, result);
  return result;
}

// A random scene's speed limits (check_representable's) under psweep's key: the speed range
// given, or r for the default one (L/(8r) to L/4). A limit of the box that any motion breaks
// stays at r.
std::optional<LimitBreach> speed_breach(const RunRequest& run,
                                        const std::optional<LimitBreach>& breach) {
  if (!breach || breach->key == "r") return breach;
  if (run.speed) return LimitBreach{"speed_max", breach->problem};
  return LimitBreach{"r", "with the default speeds L/(8r) to L/4, " + breach->problem};
}

// A random scene: room for N disks (Oler's bound for any placement, then psim's own placement),
// and speeds within check_representable's limits. Both are decided from the header and the speed
// range where they can be (below); otherwise the scene is drawn exactly as psim would draw it,
// up to kMaxDrawnToCheck particles.
std::optional<LimitBreach> random_scene_breach(const RunRequest& run) {
  const SceneHeader& h = run.header;
  if (std::string problem = packing_problem(h.n, h.L, h.r); !problem.empty())
    return LimitBreach{"N", std::move(problem)};
  const SpeedRange range = run.speed.value_or(default_speed_range(h.L, h.r));
  const EngineInfo* engine = find_engine_info(run.options.engine);
  const bool continuous_time = engine != nullptr && engine->continuous_time;
  // The limits a speed bound decides: check_representable's, and the continuous-time engine's.
  const auto limits = [&](const detail::SpeedBound& speed) {
    auto breach = detail::representable_breach(h.L, h.r, speed, run.options.slow_factor);
    if (!breach && continuous_time) breach = detail::event_work_breach(h.L, h.r, speed, h.steps);
    return breach;
  };
  // Every particle's speed is in [min, max] up to rounding (the slack): if N particles at min
  // break a limit, every draw does; if N at max keep them all, every draw does.
  const auto at = [&](double v) { return limits(detail::uniform_speed_bound(h.n, v)); };
  if (auto breach = speed_breach(run, at(range.min * (1 - 0x1p-30)))) return breach;
  const bool speeds_fit = !at(range.max * (1 + 0x1p-30));
  if ((speeds_fit && placement_cannot_fail(h.n, h.L, h.r)) || h.n > kMaxDrawnToCheck)
    return std::nullopt;
  const Drawn drawn = draw(h, run.seed, range);
  if (!drawn.placement.empty()) return LimitBreach{"N", drawn.placement};
  return speed_breach(run, limits(drawn.speed));
}

// A scene file's particles: the limits psim checks once it has read them, at the key that can
// lift each (a larger K lowers the speed per sub-step; the rest is the file's).
std::optional<LimitBreach> given_scene_breach(const RunRequest& run) {
  const Scene& scene = *run.given;
  const detail::SpeedBound speed = detail::speed_bound(scene.particles);
  if (auto breach =
          detail::representable_breach(scene.L, scene.r, speed, run.options.slow_factor)) {
    breach->key = breach->key == "speed" ? "slow_factor" : "scene_file";
    return breach;
  }
  const EngineInfo* engine = find_engine_info(run.options.engine);
  if (engine == nullptr || !engine->continuous_time) return std::nullopt;
  auto breach = detail::event_work_breach(scene.L, scene.r, speed, scene.steps);
  if (breach) breach->key = "scene_file";
  return breach;
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
  if (auto breach =
          first({{"r", width_problem(h.L, h.r)},
                 {"r", !run.given && !run.speed ? default_speeds_problem(h.L, h.r) : ""}}))
    return breach;
  return run.given ? given_scene_breach(run) : random_scene_breach(run);
}

std::string energy_warning(const Physics& e) {
  if (std::isfinite(e.energy_initial) && std::isfinite(e.energy_final) &&
      std::isfinite(e.energy_drift))
    return "";
  return fmt::format(
      "the kinetic energy is not finite (initial {}, final {}, drift {}): it is beyond the "
      "largest double, {:.3g}",
      e.energy_initial, e.energy_final, e.energy_drift, std::numeric_limits<double>::max());
}

}  // namespace particle
