#pragma once
// What a run pays before its first sub-step: the start of a process (fork, exec, the dynamic
// loader, libstdc++'s and libgomp's set-up: this program is linked as psim is) and of an OpenMP
// team (the first parallel region creates the threads), and the fork-join of a warm team (what
// every parallel region costs afterwards); and psim's own start beside that empty process.
#include <string>
#include <vector>

namespace ceilings {

// Seconds from spawning `argv` (its stdout to /dev/null) to reaping it, once per repetition.
std::vector<double> time_processes(const std::vector<std::string>& argv, int repetitions);

// The first parallel region of this process on `threads` threads, in seconds: meaningful once per
// process (ceilings --team runs it in a fresh one).
double first_team_s(int threads);

// The mean seconds of one empty parallel region on a warm team of `threads`, over `regions`.
double warm_region_s(int threads, int regions);

// Runs `argv` (ceilings --team) and reads the one number it prints; repetitions of it.
std::vector<double> child_figures(const std::vector<std::string>& argv, int repetitions);

}  // namespace ceilings
