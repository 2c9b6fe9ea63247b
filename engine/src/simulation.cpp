// simulate(): validates the run options, sets up the working state (velocities per sub-step),
// runs the chosen engine and converts the state back to time units.
#include "particle/simulation.hpp"

#include <omp.h>

#include <stdexcept>
#include <string>

#include "engines.hpp"

namespace particle {

namespace {

bool is_power_of_two(int k) { return k > 0 && (k & (k - 1)) == 0; }

}  // namespace

void validate(const RunOptions& options) {
  if (!detail::find_engine(options.engine)) {
    std::string known;
    for (const auto& e : engine_names()) known += (known.empty() ? "" : ", ") + e;
    throw std::invalid_argument("engine: unknown engine \"" + options.engine +
                                "\" (known: " + known + ")");
  }
  if (!is_power_of_two(options.slow_factor))
    throw std::invalid_argument("slow factor: must be a power of two, got " +
                                std::to_string(options.slow_factor));
  if (options.grid < 1 || options.grid > kMaxGrid)
    throw std::invalid_argument("grid: G must be between 1 and " + std::to_string(kMaxGrid) +
                                ", got " + std::to_string(options.grid));
  if (options.threads < 0)
    throw std::invalid_argument("threads: must be at least 1, got " +
                                std::to_string(options.threads));
}

RunReport simulate(Scene& scene, const RunOptions& options, const StepObserver& observer) {
  validate(options);
  const detail::EngineEntry* engine = detail::find_engine(options.engine);

  Particles& p = scene.particles;
  const std::size_t n = p.size();
  const double dt = 1.0 / options.slow_factor;  // exact: K is a power of two
  std::vector<double> ux(n), uy(n);
  for (std::size_t i = 0; i < n; ++i) {
    ux[i] = p.vx[i] * dt;
    uy[i] = p.vy[i] * dt;
  }
  const detail::World w =
      detail::make_world(scene.L, scene.r, n, p.x.data(), p.y.data(), ux.data(), uy.data(),
                         p.pair_collisions.data(), p.wall_collisions.data());

  const auto to_time_units = [&] {
    for (std::size_t i = 0; i < n; ++i) {
      p.vx[i] = ux[i] * options.slow_factor;
      p.vy[i] = uy[i] * options.slow_factor;
    }
  };
  detail::PipelineParams params;
  params.steps = scene.steps;
  params.slow_factor = options.slow_factor;
  params.threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  params.profile = options.profile;
  if (observer)
    params.on_time_unit = [&](std::int64_t step) {
      to_time_units();
      observer(step, p);
    };
  const double energy_initial = kinetic_energy(p);
  RunReport report = engine->run(w, options, params);
  to_time_units();
  report.physics.energy_initial = energy_initial;
  report.physics.energy_final = kinetic_energy(p);
  return report;
}

}  // namespace particle
