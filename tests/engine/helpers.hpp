#pragma once
// Shared by the engine tests: scenes from files or text, a run with chosen options, and the
// comparison of two runs' outcomes.
#include <gtest/gtest.h>
#include <sched.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/random_scene.hpp"
#include "particle/simulation.hpp"

namespace particle::testing {

// The first CPU of `all` alone: to pin a thread to one of the CPUs it may use.
inline cpu_set_t first_cpu_of(const cpu_set_t& all) {
  cpu_set_t one;
  CPU_ZERO(&one);
  for (int id = 0; id < CPU_SETSIZE; ++id)
    if (CPU_ISSET(id, &all)) {
      CPU_SET(id, &one);
      break;
    }
  return one;
}

inline Scene scene_from_text(const std::string& text, const RandomInit& init = {}) {
  std::istringstream in(text);
  return read_scene(in, "test", init);
}

inline Scene scene_from_file(const std::string& name) {
  const std::string path = std::string(SCENES_DIR) + "/" + name;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  return read_scene(in, path, {});
}

// A random scene of the 2019 kind: header only, particles from the seed.
inline Scene random_scene(int n, double L, double r, int steps, std::uint64_t seed = 3210,
                          std::optional<SpeedRange> speed = {}) {
  std::ostringstream text;
  text << n << "\n" << L << "\n" << r << "\n" << steps << "\nperf\n";
  return scene_from_text(text.str(), RandomInit{seed, speed});
}

// A random scene's speed range, slow to fast per time unit.
inline SpeedRange speeds(double slow, double fast) { return {slow, fast}; }

// The state hash after every time unit (what print mode writes) and at the end, from `simulate`
// or another function of its signature (an engine's host twin), on `threads` threads (0: OpenMP's
// default).
using Simulate = RunReport (*)(Scene&, const RunOptions&, const StepObserver&);
inline std::vector<std::uint64_t> unit_hashes(Scene scene, const std::string& engine,
                                              int slow_factor, Simulate run = simulate,
                                              int threads = 0) {
  std::vector<std::uint64_t> hashes;
  RunOptions options;
  options.engine = engine;
  options.slow_factor = slow_factor;
  options.threads = threads;
  run(scene, options, [&](std::int64_t, const Particles& p) { hashes.push_back(state_hash(p)); });
  hashes.push_back(state_hash(scene.particles));
  return hashes;
}

inline RunReport run(Scene& scene, const std::string& engine = "brute", int threads = 1,
                     int slow_factor = 1, int grid = 8,
                     WallStop wall_stop = WallStop::per_coordinate,
                     Overlap overlap = Overlap::approaching) {
  RunOptions options;
  options.engine = engine;
  options.threads = threads;
  options.slow_factor = slow_factor;
  options.grid = grid;
  options.wall_stop = wall_stop;
  options.overlap = overlap;
  return simulate(scene, options);
}

// A run's final state hash and its report.
struct Outcome {
  std::uint64_t hash;
  RunReport report;
};

inline Outcome outcome(Scene scene, const std::string& engine, int threads, int slow_factor = 1,
                       int grid = 8, WallStop wall_stop = WallStop::per_coordinate,
                       Overlap overlap = Overlap::approaching) {
  RunReport report = run(scene, engine, threads, slow_factor, grid, wall_stop, overlap);
  return {state_hash(scene.particles), report};
}

// The same final state and counters; pair_tests aside (each broad phase prunes its own way).
inline void expect_same(const Outcome& got, const Outcome& want) {
  EXPECT_EQ(got.hash, want.hash);
  const Counters &a = got.report.counters, &b = want.report.counters;
  EXPECT_EQ(a.candidates, b.candidates);
  EXPECT_EQ(a.pair_candidates, b.pair_candidates);  // the pairs the scene needed: engine-free
  EXPECT_EQ(a.pair_collisions, b.pair_collisions);
  EXPECT_EQ(a.wall_collisions, b.wall_collisions);
  EXPECT_EQ(a.dropped, b.dropped);
  EXPECT_EQ(a.overlaps, b.overlaps);
  EXPECT_EQ(a.receding_overlaps, b.receding_overlaps);
  EXPECT_EQ(a.wall_stops, b.wall_stops);
}

}  // namespace particle::testing
