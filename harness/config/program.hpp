// Programs: external simulators a config declares beside psim's engines (docs/programs.md), run
// with the same pinning, repetitions and measurements, fed the configuration's scene as an
// explicit particle file and judged by `psim check`.
//
//   "programs": {"mine": {"command": ["./my_sim", "{T}"], "input": "stdin", "uses": ["T"],
//                         "limits": {"memory_mib": 4096}, "env": {"MY_SIM_VERBOSE": "0"}}}
//
// The command's placeholders are {T}, {P}, {N}, {K} and {scene} ({{ and }} are literal braces). A
// program of P ranks lists "P" in `uses` and starts them itself ({P}: its mpirun -np {P}). A
// program that reads K at run time lists "slow_factor" in `uses`; one that was built for one K
// says which (`slow_factor`, default 1), and a configuration at another K is refused.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.hpp"

namespace psweep {

// Every problem with the `programs` key: a ConfigError at the key path
// ("programs.mine.command[1]"). `limits`: the config's, which a program's own keys override.
std::vector<Program> parse_programs(const Json& programs, const Limits& limits);

// A `limits` object (the config's or a program's) over `defaults`; a ConfigError at `path`.
Limits parse_limits(const Json& limits, const std::string& path, const Limits& defaults);

// `text` with each {NAME} replaced by value(NAME), "{{" and "}}" by single braces. Throws
// ConfigError "<path>: ..." for an unmatched brace; `value` decides which names exist.
std::string substitute(std::string_view text, const std::string& path,
                       const std::function<std::string(const std::string& name)>& value);

// The program's argv for one run: placeholders filled from `params`, the scene at `scene`, and
// argv[0] found on PATH when it names no directory (as a shell would).
std::vector<std::string> program_arguments(const Program& program, const Params& params,
                                           const std::string& scene);

// argv[0] as run: a name without '/' looked up on PATH (unchanged when not found there, so the
// run fails saying it cannot execute it).
std::string resolve_executable(const std::string& command);

// The most bytes a 2019 output of `scene` in its mode can take, for a program that prints
// without end: its lines (N per printed state) times the longest line a correct output holds
// (positions within L, speeds within the one the energy allows, counts of 20 digits), doubled
// for any padding between fields.
std::uint64_t output_limit(const particle::Scene& scene);

// FNV-1a-64 of the file's bytes in hex ("fnv1a64:..."); empty when it cannot be read.
std::string file_hash(const std::string& path);

}  // namespace psweep
