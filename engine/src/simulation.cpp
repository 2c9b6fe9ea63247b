// simulate(): validates the run options and the scene, sets up the working state (the engine's
// length unit, velocities per sub-step), runs the chosen engine and converts the state back.
#include "particle/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "engines.hpp"
#include "mpi/engine.hpp"
#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "scale.hpp"

namespace particle {

namespace {

bool is_power_of_two(int k) { return k > 0 && (k & (k - 1)) == 0; }

// The reading of `all` whose name() is `text`.
template <class Reading, std::size_t N>
std::optional<Reading> by_name(const Reading (&all)[N], std::string_view (*name)(Reading),
                               std::string_view text) {
  for (const Reading reading : all)
    if (name(reading) == text) return reading;
  return std::nullopt;
}

}  // namespace

std::optional<LimitBreach> option_breach(const RunOptions& options) {
  if (!detail::find_engine(options.engine)) {
    std::string known;
    for (const auto& e : engine_names()) known += (known.empty() ? "" : ", ") + e;
    return LimitBreach{"engine",
                       "unknown engine \"" + options.engine + "\" (known: " + known + ")"};
  }
  if (!is_power_of_two(options.slow_factor) || options.slow_factor > kMaxSlowFactor)
    return LimitBreach{"slow_factor", "must be a power of two from 1 to " +
                                          std::to_string(kMaxSlowFactor) + ", got " +
                                          std::to_string(options.slow_factor)};
  if (options.grid < 1 || options.grid > kMaxGrid)
    return LimitBreach{"G", "G must be between 1 and " + std::to_string(kMaxGrid) + ", got " +
                                std::to_string(options.grid)};
  if (options.threads < 0 || options.threads > max_threads())
    return LimitBreach{"T", "must be from 1 to " + std::to_string(max_threads()) + ", got " +
                                std::to_string(options.threads)};
  return std::nullopt;
}

void validate(const RunOptions& options) {
  // psim's own words for the keys (its options are --slow-factor, --grid, --threads).
  static const std::pair<std::string_view, std::string_view> kLabels[] = {
      {"engine", "engine"}, {"slow_factor", "slow factor"}, {"G", "grid"}, {"T", "threads"}};
  if (const auto breach = option_breach(options))
    for (const auto& [key, label] : kLabels)
      if (key == breach->key)
        throw std::invalid_argument(std::string(label) + ": " + breach->problem);
}

std::string_view wall_stop_name(WallStop reading) {
  return reading == WallStop::whole_motion ? "whole-motion" : "per-coordinate";
}

std::optional<WallStop> wall_stop_from_name(std::string_view name) {
  return by_name(kWallStops, wall_stop_name, name);
}

std::string_view overlap_name(Overlap reading) {
  return reading == Overlap::always ? "always" : "approaching";
}

std::optional<Overlap> overlap_from_name(std::string_view name) {
  return by_name(kOverlaps, overlap_name, name);
}

int max_threads() { return std::min(kMaxThreads, omp_get_thread_limit()); }

int resolve_threads(int threads) { return threads > 0 ? threads : omp_get_max_threads(); }

RunReport simulate(Scene& scene, const RunOptions& options, const StepObserver& observer) {
  validate(options);
  if (const std::string why = engine_unavailable(options.engine); !why.empty())
    throw InputError("engine " + options.engine + ": " + why);
  return detail::simulate_with(scene, options, observer, detail::find_engine(options.engine)->run);
}

detail::PipelineParams detail::pipeline_params(const RunOptions& options, std::int64_t steps) {
  PipelineParams params;
  params.steps = steps;
  params.slow_factor = options.slow_factor;
  params.threads = resolve_threads(options.threads);
  params.profile = options.profile;
  params.stop = options.stop;
  return params;
}

RunReport follow(const RunOptions& options) {
  validate(options);
  if (options.engine != "mpi")
    throw std::invalid_argument("engine " + options.engine +
                                ": a run of one process has no followers (only mpi's has)");
  if (const std::string why = engine_unavailable(options.engine); !why.empty())
    throw InputError("engine " + options.engine + ": " + why);
  return detail::mpi::follow(detail::pipeline_params(options, 0));
}

RunReport detail::simulate_with(Scene& scene, const RunOptions& options,
                                const StepObserver& observer, const StageRun& run) {
  Particles& p = scene.particles;
  const detail::SpeedBound speed = detail::speed_bound(p);
  const detail::EngineEntry* engine = detail::find_engine(options.engine);
  detail::check_representable(scene, speed, options.slow_factor, "scene",
                              engine->info.continuous_time);

  // The engine computes in its own length unit (scale.hpp): positions times 2^k in place,
  // velocities per sub-step times 2^k / K; both exact, undone exactly at every output.
  const std::size_t n = p.size();
  const int k_log2 = std::ilogb(static_cast<double>(options.slow_factor));  // K = 2^k_log2
  const int unit =
      detail::length_exponent(scene.L, scene.contact_distance(), speed, options.slow_factor);
  std::vector<double> ux, uy, wall_impulse(n, 0.0);
  detail::to_displacements(p, unit, options.slow_factor, ux, uy);
  detail::scale_lengths(p.x.data(), n, unit);
  detail::scale_lengths(p.y.data(), n, unit);
  detail::World w = detail::make_world(
      std::ldexp(scene.L, unit), std::ldexp(scene.r, unit), n, p.x.data(), p.y.data(), ux.data(),
      uy.data(), p.pair_collisions.data(), p.wall_collisions.data(), wall_impulse.data());
  w.whole_motion = options.wall_stop == WallStop::whole_motion;
  w.overlaps_collide = options.overlap == Overlap::always;

  const auto to_scene_units = [&] {
    p.vx.resize(n);  // after a release, restore_state left the velocities out (their first use)
    p.vy.resize(n);
    detail::scale_lengths(p.x.data(), n, -unit);
    detail::scale_lengths(p.y.data(), n, -unit);
    detail::scale_lengths(ux.data(), p.vx.data(), n, k_log2 - unit);
    detail::scale_lengths(uy.data(), p.vy.data(), n, k_log2 - unit);
  };
  detail::PipelineParams params = detail::pipeline_params(options, scene.steps);
  // The state's arrays, all of them n long: the World's, and the scene's velocities (the
  // output's alone: to_scene_units allocates them again, so that a restored World and the engine's
  // own copy of the state are not held beside them).
  const auto for_each_array = [&](auto&& each, bool velocities) {
    each(p.x), each(p.y), each(ux), each(uy), each(wall_impulse), each(p.pair_collisions);
    each(p.wall_collisions);
    if (velocities) each(p.vx), each(p.vy);
  };
  params.release_state = [&] {
    for_each_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); }, true);
  };
  params.restore_state = [&] {
    for_each_array([n](auto& v) { v.resize(n); }, false);
    w = detail::over_arrays(w, n, p.x.data(), p.y.data(), ux.data(), uy.data(),
                            p.pair_collisions.data(), p.wall_collisions.data(),
                            wall_impulse.data());
    return w;
  };
  if (observer)
    params.on_time_unit = [&](std::int64_t step) {
      to_scene_units();
      observer(step, p);
      detail::scale_lengths(p.x.data(), n, unit);  // back to the engine's unit, exactly
      detail::scale_lengths(p.y.data(), n, unit);
    };
  const EnergyMeter energy(p);  // p.vx, p.vy are still in the scene's units here
  RunReport report = run(w, options, params);
  to_scene_units();
  report.physics.energy_initial = energy.initial();
  report.physics.energy_final = kinetic_energy(p);
  report.physics.energy_drift = energy.drift(p);
  // In particle order (the arrays are back in it): the same bits for every engine that computes
  // the same collisions, whatever its threads or slot order. Converted like a velocity.
  double impulse = 0;
  for (double each : wall_impulse) impulse += each;
  report.physics.wall_impulse = std::ldexp(impulse, k_log2 - unit);
  return report;
}

}  // namespace particle
