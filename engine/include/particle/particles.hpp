#pragma once
// Particle state as structure-of-arrays: hot loops stream the coordinate they need, and the
// narrow phase vectorizes over j with unit-stride loads.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace particle {

struct Particles {
  std::vector<double> x, y;    // position, in [r, L-r]
  std::vector<double> vx, vy;  // velocity per time unit (not per sub-step)
  std::vector<std::uint64_t> pair_collisions, wall_collisions;

  explicit Particles(std::size_t n = 0)
      : x(n), y(n), vx(n), vy(n), pair_collisions(n), wall_collisions(n) {}
  std::size_t size() const { return x.size(); }
};

// Kinetic energy with unit mass: sum of (vx^2 + vy^2) / 2, summed in units of a power of two
// of the largest speed so that no intermediate square overflows or underflows (the result itself
// is 0 or infinite only where the energy is beyond a double).
double kinetic_energy(const Particles& p);

// Relative energy change of a run at any scale: energies are summed in one power-of-two unit fixed
// from the initial state, so the drift is computed even where the energy underflows a double.
class EnergyMeter {
 public:
  explicit EnergyMeter(const Particles& initial);
  double initial() const { return initial_; }  // kinetic_energy(initial)
  double drift(const Particles& now) const;    // (E_now - E_initial) / E_initial; 0 at rest

 private:
  int exp2_;
  double scaled_initial_;  // sum of v^2 in units of 2^(2 exp2)
  double initial_;
};

// FNV-1a over the bytes of every state array, printed as 16 hex digits. Bit-identical states
// give equal hashes; that is how determinism across engines and thread counts is proven.
std::uint64_t state_hash(const Particles& p);

}  // namespace particle
