#pragma once
// The declaration of what a run is: every engine and every metric, named once, here.
//
// Programs above the engine never name an engine or a metric: psim writes its --metrics JSON by
// walking metrics(), `psim --describe` prints describe_json(), psweep expands sweeps and writes
// runs.csv columns from that JSON, and the analysis takes its column groups and engine facts from
// the copy psweep keeps in meta.json. Adding an engine is one entry in engines.cpp; adding a
// metric is a field of RunReport filled by the engine plus one row of kMetrics in describe.cpp.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "particle/profile.hpp"

namespace particle {

// The run parameters that some engine ignores. The keys are the names of psweep's config keys and
// runs.csv columns; `option` is psim's flag.
enum class Param : unsigned {
  threads = 1u << 0,
  grid = 1u << 1,
  slow_factor = 1u << 2,
  wall_stop = 1u << 3,
  ranks = 1u << 4,
  overlap = 1u << 5,
};

struct ParamInfo {
  Param param;
  std::string_view key;     // "T", "G", "slow_factor", "wall_stop", "P"
  // "--threads", "--grid", "--slow-factor", "--wall-stop"; "" for P, which the launcher sets
  // (mpirun -np P), not psim
  std::string_view option;
  std::string_view about;
};
std::span<const ParamInfo> params();

// How the work of one sub-step grows with N at a fixed density, for cost estimates (psweep balances
// shards and estimates a sweep's duration with it): quadratic tests every pair; linear finds the
// pairs through cells or a sort (or, event-driven, processes a number of events that grows as N).
enum class Growth { linear, quadratic };
std::string_view to_string(Growth growth);  // "N", "N^2"

struct EngineInfo {
  std::string_view name;
  bool exact = true;  // drops no collision the model has (false: an unsafe shortcut)
  // Bit-identical final state to the reference's: the same discrete model whatever the broad
  // phase. False for an inexact engine and for a different dynamics (event-driven).
  bool matches_reference = true;
  bool reference = false;  // the engine every other one is tested and timed against (brute)
  unsigned uses = 0;       // Param bits this engine reads; the others do not change its result
  Growth growth = Growth::linear;
  // Nanoseconds of one sub-step (a time unit without sub-steps) per unit of growth, a particle or
  // for N^2 a pair, on one thread, for the same estimates; 0: not measured (psweep then uses its
  // default). Measured on one machine and scene (kEngines in engines.cpp): good to about 2x.
  double cost_ns = 0;
  // For N growth, nanoseconds more per particle and sub-step for each particle expected within a
  // sub-step's reach of it (psweep's reach_neighbours): the candidates a fast scene makes the
  // broad phase test, which a slow one does not (the crowd: cells 52 ns per particle, the default
  // scene 338 ns); 0 for a cost that does not grow with them.
  double neighbour_ns = 0;
  std::string_view about;
  // Continuous-time dynamics (no sub-steps): with `exact`, the model's true trajectory, against
  // which the discrete engines' error at each slow factor is measured (make accuracy).
  bool continuous_time = false;
  bool uses_param(Param p) const { return (uses & static_cast<unsigned>(p)) != 0; }
};
// In `psim --list-engines` order.
std::span<const EngineInfo> engines();
// nullptr for an unknown name.
const EngineInfo* find_engine_info(std::string_view name);
// Why this process cannot run the engine, "" when it can (and for an unknown name): the `gpu`
// engine needs a build with CUDA and a device. Loops over every engine skip those it names.
std::string engine_unavailable(std::string_view name);
// The engines this process can run, in engines() order.
std::vector<std::string> runnable_engines();

// What a metric measures, which decides where it goes: stage times under "stages" in --metrics
// and in the stage-time plots; counters under "counters"; the ranks' traffic (the mpi engine's
// alone) under "ranks"; physics and status at the top level.
enum class MetricKind { stage_time, counter, physics, status, rank };
std::string_view to_string(MetricKind kind);
std::string_view section(MetricKind kind);  // the --metrics object holding it; "" = top level

// A metric's value: real (a double), count (a non-negative integer) or flag (true/false; a CSV
// cell 1/0); absent where the metric does not apply to the run (the ranks' traffic of a run in
// one process), so that --metrics leaves it out and its CSV cell is empty, not 0.
struct MetricValue {
  enum class Type { real, count, flag } type = Type::real;
  double real = 0;
  std::uint64_t count = 0;
  bool flag = false;
  bool present = true;
  static MetricValue of(double v) { return {Type::real, v, 0, false}; }
  static MetricValue of(std::uint64_t v) { return {Type::count, 0, v, false}; }
  static MetricValue of(bool v) { return {Type::flag, 0, 0, v}; }
  static MetricValue absent() { return {Type::real, 0, 0, false, false}; }
};
std::string_view to_string(MetricValue::Type type);

struct MetricInfo {
  std::string_view key;  // the --metrics key and the runs.csv column
  MetricKind kind;
  MetricValue::Type type;
  std::string_view unit;  // "s", "1" (a count or a ratio), "time units", ...
  std::string_view about;
  MetricValue (*value)(const RunReport&);
};
// In runs.csv column order.
std::span<const MetricInfo> metrics();

// {"params": [...], "engines": [...], "metrics": [...]}: the tables above as JSON, for
// `psim --describe` and, through psweep, meta.json.
std::string describe_json();

}  // namespace particle
