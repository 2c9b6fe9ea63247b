#pragma once
#include <cstdint>
#include <string>

#include "particle/particles.hpp"

namespace particle {

enum class OutputMode { print, perf };

// One simulation's input: the box [0, L]^2, N disks of radius r, S time units.
struct Scene {
  double L = 0;
  double r = 0;
  std::int64_t steps = 0;
  OutputMode mode = OutputMode::perf;
  Particles particles;
  bool generated = false;  // placed from a seed (the input had no particle lines)

  std::size_t size() const { return particles.size(); }
  double contact_distance() const { return 2 * r; }
};

}  // namespace particle
