#pragma once
// The table of engines: one entry per name, each instantiating run_pipeline with its broad phase.
#include <string_view>

#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "pipeline.hpp"

namespace particle::detail {

using EngineRun = RunReport (*)(const World&, const RunOptions&, const PipelineParams&);

struct EngineEntry {
  std::string_view name;
  EngineRun run;
  bool exact = true;  // finds brute's candidates; false only for the deliberately unsafe ones
};

// nullptr for an unknown name.
const EngineEntry* find_engine(std::string_view name);

}  // namespace particle::detail
