#include <cstring>

#include "particle/particles.hpp"

namespace particle {

double kinetic_energy(const Particles& p) {
  double e = 0;
  for (std::size_t i = 0; i < p.size(); ++i) e += 0.5 * (p.vx[i] * p.vx[i] + p.vy[i] * p.vy[i]);
  return e;
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
