#include <cmath>
#include <cstring>

#include "particle/particles.hpp"
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
void fnv1a(std::uint64_t& h, const std::vector<T>& v) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
  for (std::size_t k = 0; k < v.size() * sizeof(T); ++k) {
    h ^= bytes[k];
    h *= 0x100000001b3ull;
  }
}

}  // namespace

std::uint64_t state_hash(const Particles& p) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  fnv1a(h, p.x);
  fnv1a(h, p.y);
  fnv1a(h, p.vx);
  fnv1a(h, p.vy);
  fnv1a(h, p.pair_collisions);
  fnv1a(h, p.wall_collisions);
  return h;
}

}  // namespace particle
