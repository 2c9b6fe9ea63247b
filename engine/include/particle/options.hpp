#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace particle {

// What to run a scene with. The engine is a name so that programs and configs share one list
// (engine_names()); each name maps to a compile-time broad phase, never a virtual call per pair.
struct RunOptions {
  std::string engine = "auto";
  int threads = 0;      // 0: OpenMP's default (OMP_NUM_THREADS or the cores)
  int grid = 8;         // G for the grid engine
  int slow_factor = 1;  // K sub-steps of 1/K per time unit; a power of two
  bool profile = false; // time the stages (costs two clock reads per stage per sub-step)
};

// Names accepted by RunOptions::engine, in the order `psim --list-engines` prints them.
const std::vector<std::string>& engine_names();
bool is_engine(std::string_view name);

}  // namespace particle
