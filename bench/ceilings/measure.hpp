#pragma once
// The machine's ceilings, measured (docs/performance.md, "The machine's ceilings"): the pair
// kernel's peak, memory bandwidth, the caches, process and OpenMP start-up, each figure with its
// spread, as one JSON object (what `ceilings` prints and psweep records in meta.json).
#include <nlohmann/json.hpp>
#include <string>

namespace ceilings {

struct Options {
  std::string self;        // this program, run again for --exit and --team
  int repetitions = 7;     // of every timed figure (start-ups: 3x as many, they are short)
  double kernel_s = 0.03;  // seconds of one timing of the pair kernel
};

nlohmann::json measure(const Options& options);

// A short table of the figures, for a person.
std::string table(const nlohmann::json& ceilings);

}  // namespace ceilings
