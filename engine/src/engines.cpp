#include "engines.hpp"

#include <array>
#include <stdexcept>
#include <string>

#include "broad_phase_auto.hpp"
#include "broad_phase_brute.hpp"
#include "broad_phase_cells.hpp"
#include "broad_phase_grid.hpp"
#include "broad_phase_sweep.hpp"
#include "event_simulation.hpp"

namespace particle {
namespace detail {
namespace {

RunReport run_brute(const World& w, const RunOptions&, const PipelineParams& params) {
  BruteBroadPhase broad;
  return run_pipeline(broad, w, params);
}

RunReport run_grid(const World& w, const RunOptions& options, const PipelineParams& params) {
  GridBroadPhase broad(options.grid);
  return run_pipeline(broad, w, params);
}

// The 2019 report's pruning: the reach assumes no particle moves more than L/4 per time unit,
// which collisions exceed, so it drops collisions. Opt-in, for showing how many.
RunReport run_grid_unsafe(const World& w, const RunOptions& options, const PipelineParams& params) {
  GridBroadPhase broad(options.grid, w.L / 4 / options.slow_factor);
  return run_pipeline(broad, w, params);
}

RunReport run_cells(const World& w, const RunOptions&, const PipelineParams& params) {
  CellsBroadPhase broad;
  return run_pipeline(broad, w, params);
}

RunReport run_sweep(const World& w, const RunOptions&, const PipelineParams& params) {
  SweepBroadPhase broad;
  return run_pipeline(broad, w, params);
}

// `auto` picks the cheapest correct engine for the scene and reports it as "auto:<engine>".
RunReport run_auto(const World& w, const RunOptions&, const PipelineParams& params) {
  AutoBroadPhase broad;
  return run_pipeline(broad, w, params);
}

constexpr std::array kEngines = {
    EngineEntry{"auto", run_auto},
    EngineEntry{"brute", run_brute},
    EngineEntry{"grid", run_grid},
    EngineEntry{"cells", run_cells},
    EngineEntry{"sweep", run_sweep},
    EngineEntry{"grid-unsafe", run_grid_unsafe, false, true},
    EngineEntry{"event", run_event, false},
};

}  // namespace

const EngineEntry* find_engine(std::string_view name) {
  for (const EngineEntry& e : kEngines)
    if (e.name == name) return &e;
  return nullptr;
}

}  // namespace detail

bool is_exact(std::string_view engine) {
  const detail::EngineEntry* e = detail::find_engine(engine);
  return e && e->exact;
}

bool drops_collisions(std::string_view engine) {
  const detail::EngineEntry* e = detail::find_engine(engine);
  return e && e->drops_collisions;
}

const std::vector<std::string>& engine_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : detail::kEngines) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

}  // namespace particle
