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

// The same for psweep's own: $PSWEEP_CEILINGS, else `ceilings` next to psweep (the same CMake
// build as psim's), cached in ceilings-cache/ beside it.
Json machine_ceilings();

}  // namespace psweep
