#pragma once
// The table of engines: one entry per name; the discrete ones instantiate run_pipeline with their
// broad phase, event runs its own simulation (event/simulation.hpp).
#include <string>
#include <string_view>

#include "particle/describe.hpp"
#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "particle/simulation.hpp"
#include "step/pipeline.hpp"

namespace particle::detail {

using EngineRun = RunReport (*)(const World&, const RunOptions&, const PipelineParams&);

// An engine: its public declaration (name, exactness, parameters used) and how it runs.
struct EngineEntry {
  EngineInfo info;
  EngineRun run;
  // Why this process cannot run it ("" when it can); none: it always can.
  std::string (*unavailable)() = nullptr;
};

// nullptr for an unknown name.
const EngineEntry* find_engine(std::string_view name);

// simulate() (particle/simulation.hpp) with `run` in place of the engine's own: options.engine
// still decides the limits checked. For tests of an engine's host twin (gpu/host_executor.hpp).
RunReport simulate_with(Scene& scene, const RunOptions& options, const StepObserver& observer,
                        EngineRun run);

}  // namespace particle::detail
