#include "engines.hpp"

#include <array>
#include <stdexcept>
#include <string>

#include "broad_phase/auto.hpp"
#include "broad_phase/bands.hpp"
#include "broad_phase/brute.hpp"
#include "broad_phase/cell_order.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/grid.hpp"
#include "broad_phase/sweep.hpp"
#include "event/simulation.hpp"
#include "gpu/engine.hpp"
#include "mpi/engine.hpp"

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
  return run_in_cell_order(broad, w, params);
}

RunReport run_sweep(const World& w, const RunOptions&, const PipelineParams& params) {
  SweepBroadPhase broad;
  return run_pipeline(broad, w, params);
}

RunReport run_bands(const World& w, const RunOptions&, const PipelineParams& params) {
  BandsBroadPhase broad;
  return run_pipeline(broad, w, params);
}

// `auto` picks the cheapest correct engine for the scene and reports it as "auto:<engine>".
RunReport run_auto(const World& w, const RunOptions&, const PipelineParams& params) {
  AutoBroadPhase broad;
  return run_in_cell_order(broad, w, params);
}

// Every discrete engine runs OpenMP threads over K sub-steps per time unit, under a wall-stop
// and an overlap reading (the event engine has no sub-steps, so none: its collisions happen at
// contact, and the rest of a step is not its notion).
constexpr unsigned kSubSteps = static_cast<unsigned>(Param::slow_factor) |
                               static_cast<unsigned>(Param::wall_stop) |
                               static_cast<unsigned>(Param::overlap);
constexpr unsigned kDiscrete = static_cast<unsigned>(Param::threads) | kSubSteps;
constexpr unsigned kGridded = kDiscrete | static_cast<unsigned>(Param::grid);
// The mpi engine runs P ranks of T threads each (the launcher starts the ranks).
constexpr unsigned kRanked = kDiscrete | static_cast<unsigned>(Param::ranks);

// The declaration of the engines (particle/describe.hpp): one entry per engine, nowhere else.
// The cost figures (psweep's estimates: cost_ns + neighbour_ns n per particle and sub-step, n the
// particles a broad phase meets in a sub-step, harness/config/shard.hpp; N^2 engines cost_ns per
// pair) are fitted to configs/cost.json's run, results/baselines/cost (a 2-core Intel Xeon VM, T =
// 1, the default build): the slow crowd and the weak study's scene (n below 1) set cost_ns, the
// default scene (n = N - 1) and the section-8 scene (K = 4) neighbour_ns, each estimate within 2x
// of its run there (tests/python/test_cost_model.py). grid's n counts the cells it scans too, so
// its figures hold over G = 1 .. 64; grid-unsafe scans the same cells (its reach is the smaller).
// event's figure is per particle and time unit on the default scene; mpi's is its P = 1 run (the
// messages of P > 1 are the cost model's own, shard.hpp); bands's from its time against sweep's
// on fast scenes of N = 1000 to 8000 (docs/performance.md). 0: not measured (gpu: no GPU).
constexpr std::array kEngines = {
    EngineEntry{{"auto", true, true, false, kDiscrete, Growth::linear, 30, 0.025,
                 "picks the cheapest exact discrete engine for the scene; reports auto:<choice>"},
                run_auto},
    EngineEntry{{"brute", true, true, true, kDiscrete, Growth::quadratic, 0.185, 0,
                 "all pairs, O(N^2): the reference"},
                run_brute},
    EngineEntry{{"grid", true, true, false, kGridded, Growth::linear, 60, 0.2,
                 "G x G cells, reach computed exactly each sub-step from the largest speed"},
                run_grid},
    EngineEntry{{"cells", true, true, false, kDiscrete, Growth::linear, 34, 0.3,
                 "cells sized from the scene, counting sort, fast outliers apart"},
                run_cells},
    EngineEntry{{"sweep", true, true, false, kDiscrete, Growth::linear, 30, 0.02,
                 "sort-and-sweep over swept bounding boxes"},
                run_sweep},
    EngineEntry{{"bands", true, true, false, kDiscrete, Growth::linear, 25, 0.011,
                 "sort-and-sweep in bands of y: swept boxes that overlap on both axes"},
                run_bands},
    EngineEntry{{"grid-unsafe", false, false, false, kGridded, Growth::linear, 60, 0.2,
                 "it assumes speeds <= L/4 per time unit, as the 2019 report did, and drops the "
                 "collisions of faster particles"},
                run_grid_unsafe},
    EngineEntry{
        {"event", true, false, false, 0, Growth::linear, 705, 0,
         "exact continuous-time event-driven dynamics: every collision, no sub-steps", true},
        run_event},
    EngineEntry{{"gpu", true, true, false, kSubSteps, Growth::linear, 0, 0,
                 "CUDA: cells by radix sort, the greedy filter in parallel rounds; brute's bits"},
                gpu::run,
                gpu::unavailable},
    EngineEntry{{"mpi", true, true, false, kRanked, Growth::linear, 45, 0.17,
                 "MPI: one run on the ranks of mpirun -np P, slabs of the box with halos as "
                 "wide as a sub-step's reach, the filter in rounds across ranks; brute's bits"},
                mpi::run,
                mpi::unavailable},
};

}  // namespace

const EngineEntry* find_engine(std::string_view name) {
  for (const EngineEntry& e : kEngines)
    if (e.info.name == name) return &e;
  return nullptr;
}

}  // namespace detail

std::span<const EngineInfo> engines() {
  static const auto infos = [] {
    std::array<EngineInfo, detail::kEngines.size()> a;
    for (std::size_t i = 0; i < a.size(); ++i) a[i] = detail::kEngines[i].info;
    return a;
  }();
  return infos;
}

const EngineInfo* find_engine_info(std::string_view name) {
  const detail::EngineEntry* e = detail::find_engine(name);
  return e ? &e->info : nullptr;
}

std::string engine_unavailable(std::string_view name) {
  const detail::EngineEntry* e = detail::find_engine(name);
  return e && e->unavailable ? e->unavailable() : "";
}

std::vector<std::string> runnable_engines() {
  std::vector<std::string> names;
  for (const EngineInfo& e : engines())
    if (engine_unavailable(e.name).empty()) names.emplace_back(e.name);
  return names;
}

bool is_exact(std::string_view engine) {
  const EngineInfo* e = find_engine_info(engine);
  return e && e->exact && e->matches_reference;
}

bool drops_collisions(std::string_view engine) {
  const EngineInfo* e = find_engine_info(engine);
  return e && !e->exact;
}

const std::vector<std::string>& engine_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const EngineInfo& e : engines()) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

}  // namespace particle
