// Expansion: a Config -> the list of distinct run configurations (RunSpec).
//
// `product` takes every combination of the sweep axes; `one-at-a-time` varies each axis alone
// around `base`; `zip` pairs the axes element by element (run i takes value i of every axis, all
// axes of one length: weak scaling, where N grows with T). A parameter the engine ignores (psim's
// declaration lists what each engine uses) is cleared before identity is computed, so an ignored
// axis does not multiply runs and duplicates collapse into their first occurrence. Order: the
// product's odometer order (last axis fastest), axis by axis for one-at-a-time, element by
// element for zip. O(runs x axes).
#pragma once

#include <string>
#include <vector>

#include "config.hpp"
#include "declaration.hpp"

namespace psweep {

struct RunSpec {
  std::string id;  // stable short id of the normalized parameters (config_id column)
  Params params;
  std::string scene_file;  // empty for a random scene
  Pin pin = Pin::none;
};

// Clears the parameters `params.engine` does not use; an engine the declaration does not know
// (a dry run without psim) keeps them all.
void drop_ignored(Params& params, const Declaration& declaration);

// The canonical "key=value;..." text the id hashes; equal text = same configuration.
std::string canonical_text(const Params& params, const std::string& scene_file, Pin pin);
// 12 hex digits of FNV-1a-64 over canonical_text.
std::string config_id(const Params& params, const std::string& scene_file, Pin pin);

// Throws ConfigError (prefixed with the file) for runs that cannot be formed: an engine without a
// parameter it uses (grid without G), one speed bound without the other, speed_min > speed_max.
std::vector<RunSpec> expand(const Config& config, const Declaration& declaration);

// One line per run for --dry-run and the progress line.
std::string describe(const RunSpec& run);

}  // namespace psweep
