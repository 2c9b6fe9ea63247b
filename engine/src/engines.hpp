#pragma once
// The table of engines: one entry per name; the discrete ones instantiate run_pipeline with their
// broad phase, event runs its own simulation (event_simulation.hpp).
#include <string_view>

#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "pipeline.hpp"

namespace particle::detail {

using EngineRun = RunReport (*)(const World&, const RunOptions&, const PipelineParams&);

struct EngineEntry {
  std::string_view name;
  EngineRun run;
  bool exact = true;              // brute's bit-identical result; false for grid-unsafe and event
  bool drops_collisions = false;  // deliberately unsafe: psim warns
};

// nullptr for an unknown name.
const EngineEntry* find_engine(std::string_view name);

}  // namespace particle::detail
