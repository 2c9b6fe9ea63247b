#pragma once
// A World over owned arrays, for unit tests of single stages.
#include <vector>

#include "world.hpp"

namespace particle::testing {

struct Body {
  double x, y, ux, uy;
};

struct WorldFixture {
  std::vector<double> x, y, ux, uy, wall_impulse;
  std::vector<std::uint64_t> pair_collisions, wall_collisions;
  detail::World w;

  WorldFixture(double L, double r, const std::vector<Body>& bodies) {
    for (const Body& b : bodies) {
      x.push_back(b.x);
      y.push_back(b.y);
      ux.push_back(b.ux);
      uy.push_back(b.uy);
    }
    pair_collisions.assign(bodies.size(), 0);
    wall_collisions.assign(bodies.size(), 0);
    wall_impulse.assign(bodies.size(), 0);
    w = detail::make_world(L, r, bodies.size(), x.data(), y.data(), ux.data(), uy.data(),
                           pair_collisions.data(), wall_collisions.data(), wall_impulse.data());
  }
};

}  // namespace particle::testing
