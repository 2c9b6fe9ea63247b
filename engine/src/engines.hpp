#pragma once
// The table of engines: one entry per name; the discrete ones instantiate run_pipeline with their
// broad phase, event runs its own simulation (event/simulation.hpp).
#include <functional>
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
// still decides the limits checked. The one place where the engine's length unit and the
// velocities per sub-step are set up and undone: for tests of an engine's host twin
// (gpu/host_executor.hpp) and for psim check's step-by-step replay (check/model.cpp), which runs
// the stages one by one on the World it is given.
// The parameters of a run of `steps` time units under `options` (the observer and the state's
// release are simulate_with's).
PipelineParams pipeline_params(const RunOptions& options, std::int64_t steps);

using StageRun = std::function<RunReport(const World&, const RunOptions&, const PipelineParams&)>;
RunReport simulate_with(Scene& scene, const RunOptions& options, const StepObserver& observer,
                        const StageRun& run);

}  // namespace particle::detail
