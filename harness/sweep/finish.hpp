// Finish: the last stage of a sweep. Records the session's cost in meta.json and says how the
// sweep ended: how many runs, the harness's overhead, and, when interrupted, how to continue.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "config/config.hpp"
#include "config/shard.hpp"
#include "sweep/run_loop.hpp"

namespace psweep {

// psweep's own CPU time so far, user and system (getrusage).
double own_cpu_s();

// The `sessions` entry of meta.json: jobs, the loop's wall time, the children's time, the
// overhead (wall - children) / children (0 when no child ran) and psweep's CPU time.
// harness_cpu_s does not depend on how busy the machine is; the wall difference does, because
// psweep must be scheduled again after each child exits.
Json session_entry(const LoopTotals& totals, double harness_cpu_s, const std::string& date);

// The command that continues an interrupted sweep, or shard, in `out`.
std::string resume_command(const std::string& config_file, const std::optional<ShardSpec>& shard,
                           const std::filesystem::path& out);

// Appends session_entry to meta["sessions"], writes meta to meta_json and reports on stderr.
// Returns the exit status: 0, or 128 + `signal` when SIGINT/SIGTERM stopped the sweep (finished
// rows are kept; the message gives `resume_command`, which continues the sweep).
int finish_sweep(Json& meta, const std::string& meta_json, const LoopTotals& totals, int signal,
                 const std::string& resume_command, const std::filesystem::path& out);

}  // namespace psweep
