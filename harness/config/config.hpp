// Sweep configuration: the JSON file parsed and validated once, at the boundary.
//
// Every problem (invalid JSON, unknown key, wrong type, value out of range) becomes a ConfigError
// whose message starts with "<file>: <key path>: ", e.g. "threads.json: sweep.T[2]: expected a
// positive integer". Nothing past this file re-validates user input.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "particle/scene.hpp"

namespace psweep {

using Json =
    nlohmann::ordered_json;  // keeps the file's key order: axes expand in the order written

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Combine { product, one_at_a_time, zip };
enum class Pin { close, spread, none };

// A CSV cell or identity field: the value's shortest text, empty when the parameter is unused.
template <class T>
std::string cell(const std::optional<T>& v) {
  return v ? fmt::format("{}", *v) : std::string();
}

const char* to_string(Pin pin);
const char* to_string(Combine combine);

// The readings a program's output must follow (psim check's --wall-stop and --overlap); an empty
// one: any.
struct RequiredReadings {
  std::optional<std::string> wall_stop, overlap;
};

// The parameters of one simulation. An empty optional is a parameter the run does not use (those
// psim's declaration says its engine ignores; seed and speeds with a scene file); it is neither
// passed to psim nor part of the configuration's identity, and its CSV cell is empty.
inline constexpr std::string_view kDefaultWallStop = "per-coordinate";
inline constexpr std::string_view kDefaultOverlap = "approaching";

struct Params {
  std::string engine;
  std::int64_t N = 0;
  double L = 0;
  double r = 0;
  std::int64_t S = 0;
  std::optional<std::int64_t> slow_factor;
  std::optional<std::uint64_t> seed;
  std::optional<std::int64_t> T;
  std::optional<std::int64_t> P;  // MPI ranks, started by the config's launcher (launcher.hpp)
  std::optional<std::int64_t> G;
  std::optional<double> speed_min;
  std::optional<double> speed_max;
  std::string neighbour = "none";  // "busy": a spinning process on one CPU during the run
  // The model's wall-stop reading (docs/model.md, "Readings"); the default for an engine that
  // has none (event) and for a program, whose reading is its own (the check names it).
  std::string wall_stop = std::string(kDefaultWallStop);
  std::string overlap = std::string(kDefaultOverlap);  // the overlap reading, the same way
};

// The threads of one run over all its ranks, T x P (each 1 where the engine does not use it):
// what shares the CPUs (oversubscribed, the cost model, the wait policy).
inline std::int64_t run_threads(const Params& p) { return p.T.value_or(1) * p.P.value_or(1); }

// The keys `base` and `sweep` accept, in CSV column order.
const std::vector<std::string>& param_keys();

// The field of an engine parameter that an engine may ignore (T, P, G, slow_factor), by key;
// nullptr for any other key.
using OptionalParam = std::optional<std::int64_t> Params::*;
OptionalParam optional_param(const std::string& key);
// Whether an engine may ignore the parameter `key`: the optional ones, and the readings wall_stop
// and overlap (left at their defaults where ignored).
bool ignorable_param(const std::string& key);

// A number of a config, validated: a ConfigError "<path>: expected a positive ..." otherwise.
std::int64_t positive_integer(const Json& v, const std::string& path);
double positive_number(const Json& v, const std::string& path);

// Validates `value` for parameter `key` and stores it; throws ConfigError naming `path`.
void set_param(Params& params, const std::string& key, const Json& value, const std::string& path);

struct Axis {
  std::string key;
  std::vector<Json> values;  // each already validated by set_param
};

// What one run of an external program may use (docs/programs.md, "Confinement"): the config's
// `limits` for every program, a program's own `limits` over them. Wall time is the config's
// timeout_s; a program's output file has its own cap (output_limit).
struct Limits {
  double cpu_s = 0;                // CPU seconds per process; 0: timeout_s x the run's CPUs
  std::int64_t memory_mib = 2048;  // writable memory per process (RLIMIT_DATA)
  std::int64_t processes = 256;    // processes and threads, all together
  std::int64_t open_files = 256;   // per process
  std::int64_t disk_mib = 256;     // its working folder, and its /tmp, each
};

// An external program swept beside psim's engines (config/program.hpp).
// What a run can name as its engine, described alike whether psim's declaration gives it (an
// engine) or a config's `programs` entry does (a program).
struct EngineFacts {
  std::string name;
  // The run parameters that reach it ("T", "P", "G", "slow_factor"); expansion drops the others.
  // For a program: "T" and "P" when its `uses` lists them, and "slow_factor" always (the check judges its output
  // at the run's K, whether it reads K or was built for one).
  std::vector<std::string> uses;
  // The power of N that one sub-step's work grows with: 1 ("N": cells, a sort, events) or 2
  // ("N^2": every pair); 1 for an engine that does not declare it, a program's `growth` (default
  // N^2, the 2019 assignment's all-pairs method). The cost model (shard.hpp) reads it, so psweep
  // names no engine.
  int growth = 1;
  // Nanoseconds of one sub-step per unit of growth on one thread ("cost_ns"); 0 when not declared
  // (an older psim, or a program), and the cost model then uses its default for the growth.
  double cost_ns = 0;
  // Nanoseconds more per particle and sub-step per particle expected within a sub-step's reach
  // ("neighbour_ns", N growth; shard.hpp's reach_neighbours); 0 when not declared.
  double neighbour_ns = 0;
  // An external program: it runs confined (harness/run/confine.hpp), which costs a fixed time per
  // run, and psim check judges its output.
  bool program = false;
  bool uses_param(const std::string& key) const;
};

struct Program {
  EngineFacts facts;                 // its name, uses and growth, as an engine's
  std::vector<std::string> command;  // as written: placeholders unfilled
  bool input_file = false;           // "input": "file" ({scene}); else the scene on stdin
  bool takes_slow_factor = false;    // "slow_factor" in uses: it reads K at run time
  std::int64_t slow_factor = 1;      // the K it was built for, when it does not take K
  bool sub_steps_numbered = false;   // "numbers": "sub-steps": psim check --sub-steps-numbered
  Limits limits;                     // the config's, with the program's own over them
  std::vector<std::pair<std::string, std::string>> env;  // "env": variables it is given
};

// A run's time limit at most: a week, far beyond any run the lab makes, and far inside the
// nanosecond clock's range (a limit of 10^10 s overflowed it and timed every run out at once).
inline constexpr double kMaxTimeoutS = 7 * 24 * 3600;
// P at most: the mpi engine's every move is an all-to-all over every rank, which suits a few
// nodes, not thousands of ranks.
inline constexpr std::int64_t kMaxRanks = 4096;

struct Config {
  std::string file;  // as given on the command line; prefixes every message
  std::string name;
  Json raw;        // the document as parsed, for meta.json
  Json base_json;  // `base` as written, for the engine check's key paths
  Params base;     // defaults filled in: slow_factor 1, seed 3210, T 1, P 1
  std::vector<Axis> sweep;
  Combine combine = Combine::product;
  int repetitions = 1;
  int warmup = 0;
  Pin pin = Pin::none;
  double timeout_s = 600;  // at most kMaxTimeoutS
  // How long psweep waits before an external program's run for the machine to be as quiet as when
  // the sweep began; a run still busier is timed anyway and its busy_tasks say by how much.
  double quiet_wait_s = 2;
  // A sweep of more runs (repetitions counted) on one machine needs --yes or a larger max_runs:
  // 10^5 runs are about a day even at a second each.
  std::int64_t max_runs = 100000;
  std::optional<std::string> scene_file;  // as written (relative to the working directory)
  // scene_file as psim reads it: N, L, r, S, and the particles whose speeds psim's limits check.
  std::shared_ptr<const particle::Scene> scene;
  Limits limits;  // `limits`: every program's, unless its own say otherwise
  // A program's judging run: its scene in print mode, judged step by step, S capped here if
  // given. Uncapped (the default), every timed run's final state must equal the judging run's.
  std::optional<std::int64_t> judge_steps;
  // `reading` and `overlap_reading`: the readings a program's output must follow; none: any
  // (psim check names the one it follows).
  RequiredReadings reading;
  std::vector<Program> programs;  // `programs`, in the file's order
  // `launcher`: the words that start the P ranks of a run that uses P, placeholders unfilled
  // (config/launcher.hpp); default_launcher() where the config has none.
  std::vector<std::string> launcher;
  // `counters: "simulate"`: each psim configuration once more under cachegrind, whose counts fill
  // the instructions, cache_misses and branch_misses the hardware did not (run/simulated.hpp).
  bool simulate_counters = false;

  // nullptr when `engine` names no program (psim's engines).
  const Program* program(const std::string& engine) const;
};

// Parses and validates the text of a config; `file` is used in messages only.
Config parse_config(const std::string& text, const std::string& file);
// Reads `path` and parses it; an unreadable file is a ConfigError too.
Config load_config(const std::string& path);

// Reads a 2019-format input file with psim's own reader (particle::read_scene); its problems are
// ConfigErrors "scene_file: FILE:LINE: FIELD: problem".
// The whole of the file at `path`; empty where it cannot be read.
std::string read_file(const std::string& path);

std::shared_ptr<const particle::Scene> read_scene_file(const std::string& path);

// Throws ConfigError naming the first program that shadows an engine in `known`, then the first
// engine (base.engine or sweep.engine[i]) neither in `known` nor a program, then the first that
// psim declares but cannot run in this build (`unavailable`: engine -> psim's reason), so that a
// sweep of gpu without CUDA is refused before it starts, not failed run by run.
void check_engines(const Config& config, const std::vector<std::string>& known,
                   const std::map<std::string, std::string>& unavailable = {});

}  // namespace psweep
