// Expansion: a Config -> the sequence of distinct run configurations (RunSpec), produced lazily.
//
// `product` takes every combination of the sweep axes; `one-at-a-time` varies each axis alone
// around `base`; `zip` pairs the axes element by element (run i takes value i of every axis, all
// axes of one length: weak scaling, where N grows with T). A parameter the engine ignores (psim's
// declaration lists what each engine uses) is cleared before identity is computed, so an ignored
// axis does not multiply runs and duplicates collapse into their first occurrence. Order: the
// product's odometer order (last axis fastest), axis by axis for one-at-a-time, element by
// element for zip.
//
// Memory does not grow with the product: a combination is the first of its duplicates exactly when
// each digit is the lowest index of its axis giving the same value for that combination's engine
// (equal duplicates form a product of per-axis sets, whose first member in odometer order takes the
// lowest index of each). That table is computed once per engine value, O(engines x axis values),
// and the walk holds one combination at a time: O(1) memory and about one parameter update per
// combination, where it steps only over the values that are the first of their equals for some
// engine (repeated values add nothing to walk); count_configurations() counts from the table
// alone. One-at-a-time has only as many candidates as the axes have values, so it remembers the
// ones it has seen, and so does zip.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"

namespace psweep {

struct RunSpec {
  std::string id;  // stable short id of the normalized parameters (config_id column)
  Params params;
  std::string scene_file;  // empty for a random scene
  Pin pin = Pin::none;
};

// Clears the parameters `params.engine` does not use: a program's are its own (Program::uses),
// an engine's its declaration's; an engine the declaration does not know (a dry run without psim)
// keeps them all.
void drop_ignored(Params& params, const Declaration& declaration, const Config& config);

// The canonical "key=value;..." text the id hashes; equal text = same configuration.
std::string canonical_text(const Params& params, const std::string& scene_file, Pin pin);
// 12 hex digits of FNV-1a-64 over canonical_text.
std::string config_id(const Params& params, const std::string& scene_file, Pin pin);

// Calls `visit` with each distinct configuration's parameters (ignored ones cleared), in order,
// without forming ids or holding the sequence. Throws ConfigError (prefixed with the file) for runs
// that cannot be formed: an engine without a parameter it uses (grid without G), one speed bound
// without the other, speed_min > speed_max, and any run psim would refuse by its own limits
// (particle::run_limit_breach: N, S, G, T, K bounds, a random scene psim's placement cannot place
// from its seed, L/(2r), speeds beyond what doubles represent at K, random or a scene file's, and
// the event engine's box crossings), at the key path that set the value ("sweep.N[1]", "base.G",
// "scene_file").
void for_each_configuration(const Config& config, const Declaration& declaration,
                            const std::function<void(const Params&)>& visit);

// How many configurations for_each_configuration visits, computed from the per-engine tables
// of equal values without the walk (a product of 10^9 combinations is counted at once; runs that
// cannot be formed are not detected), saturating at SIZE_MAX.
std::size_t count_configurations(const Config& config, const Declaration& declaration);

// The configuration's RunSpec (its id, scene and pinning).
RunSpec make_run(const Config& config, const Params& params);

// The configurations whose 0-based position in the sequence `keep` accepts (all without `keep`),
// with a check that no two ids collide.
std::vector<RunSpec> expand(const Config& config, const Declaration& declaration,
                            const std::function<bool(std::size_t index)>& keep = {});

// One line per run for --dry-run and the progress line.
std::string describe(const RunSpec& run);

}  // namespace psweep
