#include "particle/particles.hpp"

#include <cmath>
#include <cstring>

#include "particle/hash.hpp"
#include "scale.hpp"

namespace particle {
double kinetic_energy(const Particles& p) {
  const detail::SpeedBound b = detail::speed_bound(p);
  return std::ldexp(b.sum_sq, 2 * b.exp2 - 1);
}

EnergyMeter::EnergyMeter(const Particles& initial) {
  const detail::SpeedBound b = detail::speed_bound(initial);
  exp2_ = b.exp2;
  scaled_initial_ = b.sum_sq;
  initial_ = std::ldexp(b.sum_sq, 2 * b.exp2 - 1);
}

double EnergyMeter::drift(const Particles& now) const {
  const double scaled_now = detail::scaled_sum_sq(now, exp2_);
  if (scaled_initial_ == 0) return scaled_now == 0 ? 0 : INFINITY;
  return (scaled_now - scaled_initial_) / scaled_initial_;
}

namespace {

template <class T>
void hash_into(std::uint64_t& h, const std::vector<T>& v) {
  h = fnv1a(v.data(), v.size() * sizeof(T), h);
}

}  // namespace

std::uint64_t state_hash(const Particles& p) {
  std::uint64_t h = kFnv1aBasis;
  hash_into(h, p.x);
  hash_into(h, p.y);
  hash_into(h, p.vx);
  hash_into(h, p.vy);
  hash_into(h, p.pair_collisions);
  hash_into(h, p.wall_collisions);
  return h;
}

}  // namespace particle
