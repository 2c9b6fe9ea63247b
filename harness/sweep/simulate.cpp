#include "sweep/simulate.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>

#include "config/program.hpp"
#include "run/record.hpp"
#include "sweep/run_loop.hpp"

#ifndef PSWEEP_SOURCE_DIR
#define PSWEEP_SOURCE_DIR "."
#endif

namespace fs = std::filesystem;

namespace psweep {
namespace {

// valgrind's slowdown on psim is about 50x with the cache simulation; a timeout that a plain
// run would hit is given that room, up to the most a config may ask for.
constexpr double kSlowdown = 100;

// psim-cachegrind's settings for the children of this stage only: set for its launcher, unset
// after, so that no later child sees them.
struct ScriptEnvironment {
  ScriptEnvironment(const std::string& psim, const std::string& counts) {
    setenv("REGRESS_PSIM", psim.c_str(), 1);
    setenv("REGRESS_COUNTS", counts.c_str(), 1);
    setenv("REGRESS_SIMULATE", cachegrind_options().c_str(), 1);
  }
  ~ScriptEnvironment() {
    for (const char* name : {"REGRESS_PSIM", "REGRESS_COUNTS", "REGRESS_SIMULATE"}) unsetenv(name);
  }
};

}  // namespace

std::string cannot_simulate() {
  if (std::string why = simulation_refused(); !why.empty()) return why;
  if (access(resolve_executable("valgrind").c_str(), X_OK) != 0)
    return "valgrind is not installed (scripts/bootstrap.sh installs it)";
  return "";
}

std::map<std::string, SimulatedCounts> simulate_counters(
    const Config& config, const std::vector<RunSpec>& runs, const std::vector<Job>& jobs,
    const std::vector<std::string>& inputs, const std::string& out, const std::string& psim) {
  std::set<std::size_t> wanted;  // once per configuration; external programs are not psim
  for (const Job& job : jobs)
    if (!config.program(runs[job.run].params.engine)) wanted.insert(job.run);
  std::map<std::string, SimulatedCounts> counts;
  if (wanted.empty()) return counts;
  const fs::path folder = fs::path(out) / "tmp" / "counts";
  fs::create_directories(folder);
  Config slow = config;
  slow.timeout_s = std::min(config.timeout_s * kSlowdown, kMaxTimeoutS);
  const ScriptEnvironment env(psim, folder.string());
  const Launch launch =
      child_launcher(slow, PSWEEP_SOURCE_DIR "/scripts/psim-cachegrind", nullptr, nullptr);
  std::fprintf(stderr,
               "psweep: counters: simulating %zu configurations once each under cachegrind (%s)\n",
               wanted.size(), std::getenv("REGRESS_SIMULATE"));
  for (std::size_t k : wanted) {
    const RunSpec& run = runs[k];
    const std::string metrics = (folder / (run.id + ".json")).string();
    const ChildResult child = launch(run, {inputs[k], metrics, "", 0});
    if (child.outcome == Outcome::interrupted) break;  // the sweep stops; its rows say so
    const std::string cg = (folder / (run.id + ".cg")).string();
    const auto parsed = child.outcome == Outcome::exited && child.exit_code == 0
                            ? parse_cachegrind(read_file(cg))
                            : std::nullopt;
    if (parsed)
      counts[run.id] = *parsed;
    else
      std::fprintf(stderr, "psweep: counters: %s %s not simulated: %s\n", run.id.c_str(),
                   run.params.engine.c_str(), with_tail("cachegrind's run failed", child).c_str());
    fs::remove(metrics);
    fs::remove(cg);
  }
  return counts;
}

}  // namespace psweep
