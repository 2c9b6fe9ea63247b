// The machine's ceilings for meta.json (docs/performance.md, "The machine's ceilings"): the
// `ceilings` program of this build, run once per machine and build and its JSON cached in the
// build folder, so that a sweep pays its few seconds only the first time.
#pragma once

#include <string>

#include "config/config.hpp"

namespace psweep {

// The ceilings of this machine: from `cache_dir`/<host>.json when it holds the figures of this
// very executable (its hash) on this machine (/etc/machine-id), else measured now by running it
// and cached there. Each object gets "source" ("measured" or "cached"), "executable" and
// "executable_hash". Null, with the reason on stderr once, when the program is missing or fails:
// a sweep never stops for it.
Json machine_ceilings(const std::string& executable, const std::string& cache_dir);

// `ceilings` as measured by `executable`, with its path and hash, written to its cache for this
// machine (make ceilings refreshes it so: a sweep then records the figures of a quiet moment
// rather than those a first sweep took, perhaps while tests ran beside it).
Json cache_ceilings(Json ceilings, const std::string& executable, const std::string& cache_dir);

// The cache folder of an executable's figures: ceilings-cache/ beside it.
std::string ceilings_cache(const std::string& executable);

// The same for psweep's own: $PSWEEP_CEILINGS, else `ceilings` next to psweep (the same CMake
// build as psim's), cached in ceilings_cache().
Json machine_ceilings();

}  // namespace psweep
