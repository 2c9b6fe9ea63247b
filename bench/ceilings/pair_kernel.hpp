#pragma once
// The pair kernel's peak: brute's row loop (narrow_phase.hpp's test_row, the same pre-test every
// engine's long spans take, at the vector width this build compiles) over a World small enough to
// stay in L1, so that nothing but the kernel's own arithmetic and loads is timed.
//
// The scene is a lattice of particles 2 diameters apart that all move alike: every pair's relative
// displacement is zero, so the pre-test flags no pair and no exact test (square root, division)
// runs. This is the rate of the common case, the one the engines' dilute scenes spend their narrow
// phase in; a flagged pair costs more, so an engine cannot beat it per pair test.
#include <cstdint>
#include <vector>

#include "world.hpp"

namespace ceilings {

// A World over arrays it owns: n particles in L1.
class KernelScene {
 public:
  explicit KernelScene(std::uint32_t n);
  KernelScene(const KernelScene&) = delete;
  KernelScene& operator=(const KernelScene&) = delete;
  const particle::detail::World& world() const { return w_; }

 private:
  std::vector<double> x_, y_, ux_, uy_, impulse_;
  std::vector<std::uint64_t> pair_collisions_, wall_collisions_;
  particle::detail::World w_;
};

// What the kernel did: its pair tests and candidates as the engine counts them.
struct KernelCount {
  std::uint64_t pair_tests = 0;
  std::uint64_t candidates = 0;
};

// `passes` times every pair of the scene, row by row as brute tests them.
KernelCount all_pairs(const KernelScene& scene, int passes);

// The particles whose four arrays fill at most half of an L1 data cache of `l1_bytes` (so that
// the other half holds the rest: the candidates' vector, the stack), at most 1024, at least 64.
std::uint32_t particles_for_l1(std::uint64_t l1_bytes);

// One timing of `threads` threads, each on its own scene, all running `passes`: seconds between
// the barrier before and the barrier after.
struct KernelTiming {
  double seconds = 0;
  KernelCount count;  // summed over threads
};
KernelTiming time_kernel(std::uint32_t n, int passes, int threads);

// The register width of the pre-test in this build: 512 (AVX-512: 8 lanes in one register), 256
// (AVX: two registers of 4 lanes), 128 (SSE2).
int vector_bits();

}  // namespace ceilings
