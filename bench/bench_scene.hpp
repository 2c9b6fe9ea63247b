#pragma once
// The scenes as working states (a World over owned arrays), for the benchmarks.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "particle/io.hpp"
#include "particle/random_scene.hpp"
#include "scale.hpp"
#include "world.hpp"

namespace bench {

struct SceneSpec {
  const char* name;
  int n;
  double L, r;
  int slow_factor;
  std::optional<particle::SpeedRange> speed;  // default: the 2019 range L/(8r)..L/4
};

// default: the 2019 scene; sec8: the report's section 8 scene (K = 4); crowd: a slow crowd;
// million: one million slow particles.
inline const SceneSpec kDefault{"default", 1000, 20000, 1, 1, {}};
inline const SceneSpec kSec8{"sec8", 2000, 20000, 1, 4, {}};
inline const SceneSpec kCrowd{"crowd", 20000, 2000, 1, 1, particle::SpeedRange{0.5, 1}};
inline const SceneSpec kMillion{"million", 1000000, 4000, 1, 1, particle::SpeedRange{0.05, 0.2}};

// A scene's state with displacements per sub-step, as simulate() sets it up.
struct State {
  particle::Scene scene;
  std::vector<double> ux, uy, wall_impulse;
  particle::detail::World w;

  State(const State& other)
      : scene(other.scene),
        ux(other.ux),
        uy(other.uy),
        wall_impulse(other.wall_impulse),
        w(other.w) {
    point();
  }
  State& operator=(const State&) = delete;

  explicit State(const SceneSpec& spec, std::uint64_t seed = 3210) {
    std::ostringstream text;
    text << spec.n << "\n" << spec.L << "\n" << spec.r << "\n1\nperf\n";
    std::istringstream in(text.str());
    scene = particle::read_scene(in, spec.name, particle::RandomInit{seed, spec.speed});
    // In the scene's own units (unit 0): these scenes need no rescaling, and bench_io formats
    // their positions as psim prints them.
    particle::detail::to_displacements(scene.particles, 0, spec.slow_factor, ux, uy);
    wall_impulse.assign(scene.size(), 0);
    point();
  }

  // The World's pointers into this state's own arrays.
  void point() {
    auto& p = scene.particles;
    w = particle::detail::make_world(scene.L, scene.r, p.size(), p.x.data(), p.y.data(), ux.data(),
                                     uy.data(), p.pair_collisions.data(), p.wall_collisions.data(),
                                     wall_impulse.data());
  }
};

// Pristine states, built once per scene (a million-particle placement takes a second); a
// benchmark that changes the state works on a copy.
inline State& state_of(const SceneSpec& spec) {
  static std::vector<std::pair<std::string, std::unique_ptr<State>>> cache;
  for (auto& [name, state] : cache)
    if (name == spec.name) return *state;
  cache.emplace_back(spec.name, std::make_unique<State>(spec));
  return *cache.back().second;
}

// Every benchmark reports the minimum over repetitions too (on a shared machine the minimum is
// the figure least disturbed by other processes), and runs at least 0.1 s per repetition instead
// of 0.5 s, so `make bench` (5 repetitions) takes a few minutes.
inline benchmark::internal::Benchmark* with_min(benchmark::internal::Benchmark* b) {
  return b->MinTime(0.1)->ComputeStatistics(
      "min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); });
}

}  // namespace bench
