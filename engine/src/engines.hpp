#pragma once
// The table of engines: one entry per name; the discrete ones instantiate run_pipeline with their
// broad phase, event runs its own simulation (event/simulation.hpp).
#include <string_view>

#include "particle/describe.hpp"
#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "step/pipeline.hpp"

namespace particle::detail {

using EngineRun = RunReport (*)(const World&, const RunOptions&, const PipelineParams&);

// An engine: its public declaration (name, exactness, parameters used) and how it runs.
struct EngineEntry {
  EngineInfo info;
  EngineRun run;
};

// nullptr for an unknown name.
const EngineEntry* find_engine(std::string_view name);

}  // namespace particle::detail
