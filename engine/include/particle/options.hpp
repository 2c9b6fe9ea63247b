#pragma once
#include <atomic>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace particle {

// The two readings of the 2019 specification's "stops just next to the wall" (docs/model.md,
// "Readings"): after its collision, a particle moves for the rest of the sub-step, and a wall
// line it would cross stops either the crossing coordinate alone (per_coordinate, this model's
// reading, and bannified/cs3210-ass1's) or its whole motion, where its path first meets a wall line
// (whole_motion, the 2019 authors' code and Aussiroth/cs3210-parallel-motion-simulator's).
enum class WallStop { per_coordinate, whole_motion };

// "per-coordinate", "whole-motion": the names psim's --wall-stop, configs and reports use.
std::string_view wall_stop_name(WallStop reading);
// The reading a name gives, if it names one.
std::optional<WallStop> wall_stop_from_name(std::string_view name);
// Every reading, in the order above.
inline constexpr WallStop kWallStops[] = {WallStop::per_coordinate, WallStop::whole_motion};

// The two readings of the 2019 specification's "They might overlap at the end of the step. In
// that case, the collision is computed in the next step from the overlapped positions"
// (docs/model.md, "Readings"): a pair that overlaps at a sub-step's start collides at once (t = 0)
// if it approaches (approaching, this model's reading), or whatever its motion (always: the
// collision is computed, receding or not, as Aussiroth/cs3210-parallel-motion-simulator does).
enum class Overlap { approaching, always };

// "approaching", "always": the names of psim's --overlap, configs and reports.
std::string_view overlap_name(Overlap reading);
std::optional<Overlap> overlap_from_name(std::string_view name);
inline constexpr Overlap kOverlaps[] = {Overlap::approaching, Overlap::always};

// What to run a scene with. The engine is a name so that programs and configs share one list
// (engine_names()); each name maps to a compile-time broad phase, never a virtual call per pair.
struct RunOptions {
  std::string engine = "auto";
  int threads = 0;      // 0: OpenMP's default (OMP_NUM_THREADS or the cores)
  int grid = 8;         // G for the grid engine, in [1, kMaxGrid]
  int slow_factor = 1;  // K sub-steps of 1/K per time unit; a power of two
  WallStop wall_stop = WallStop::per_coordinate;  // the event engine has no rest of a sub-step
  Overlap overlap = Overlap::approaching;  // the event engine leaves no overlap behind a step
  bool profile = false;  // time the stages (costs two clock reads per stage per sub-step)
  // A stop request, set from elsewhere (psim's SIGINT/SIGTERM handler): the engine reads it once
  // per sub-step (event: once per event) and returns early with the state reached, which
  // RunReport::interrupted and time_reached describe. Not owned; nullptr: never stops early.
  const std::atomic<bool>* stop = nullptr;
};

// G x G cells cost memory per thread: G is bounded.
inline constexpr int kMaxGrid = 4096;

// K multiplies the work: S time units are S x K sub-steps, each a full pass over the particles.
// At 2^20 one time unit of a one-particle scene is already a million sub-steps (README "Limits").
inline constexpr int kMaxSlowFactor = 1 << 20;

// Every thread keeps buffers of its own of a few bytes per particle (more for small scenes), so
// T bounds memory; beyond the cores, threads only take turns.
inline constexpr int kMaxThreads = 1024;

// The most threads a run may use: kMaxThreads, or OpenMP's thread limit (OMP_THREAD_LIMIT) where
// that is lower.
int max_threads();
// A thread count as the options give it: `threads`, or OpenMP's default (OMP_NUM_THREADS or the
// cores) where it is 0 or less.
int resolve_threads(int threads);

// A limit a run breaks: the run key it concerns, as psweep's configs and runs.csv name it (N, L,
// r, S, engine, slow_factor, T, G, speed_min), and the problem ("must be ..., got ...").
struct LimitBreach {
  std::string key;
  std::string problem;
};

// The first option no engine can honour, if any (validate()'s rules).
std::optional<LimitBreach> option_breach(const RunOptions& options);

// Throws std::invalid_argument, naming the field, for options no engine can honour: an unknown
// engine, K not a power of two in [1, kMaxSlowFactor], G outside [1, kMaxGrid], threads negative
// or beyond max_threads(). simulate() calls it;
// programs call it first to reject bad options before reading any input.
void validate(const RunOptions& options);

// True for an engine that gives the reference's bit-identical result (particle/describe.hpp:
// exact and matches_reference); false for unknown names.
bool is_exact(std::string_view engine);

// True for an engine that deliberately drops collisions (not exact in particle/describe.hpp:
// grid-unsafe, the 2019 report's fixed speed bound): psim warns.
bool drops_collisions(std::string_view engine);

// Names accepted by RunOptions::engine, in the order `psim --list-engines` prints them.
const std::vector<std::string>& engine_names();

}  // namespace particle
