#pragma once
// Shared by the engine tests: scenes from files or text, and a run with chosen options.
#include <fstream>
#include <sstream>
#include <string>

#include "particle/io.hpp"
#include "particle/random_scene.hpp"
#include "particle/simulation.hpp"

namespace particle::testing {

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

inline RunReport run(Scene& scene, const std::string& engine = "brute", int threads = 1,
                     int slow_factor = 1, int grid = 8) {
  RunOptions options;
  options.engine = engine;
  options.threads = threads;
  options.slow_factor = slow_factor;
  options.grid = grid;
  return simulate(scene, options);
}

}  // namespace particle::testing
