#pragma once
// The engine's length unit: a power of two 2^-k chosen per scene so that the contact distance s
// and the largest length M (box side, or the speed bound per sub-step) sit symmetrically around 1.
// Multiplying by a power of two is exact for normal doubles and commutes with every rounding
// (sums, products, quotients, square roots), so for any scene whose terms neither underflow nor
// overflow in the original units the result is bit-identical to computing in them; and a scene at
// 1e-200 or 1e300 is computed exactly as its copy at 1.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "particle/options.hpp"
#include "particle/particles.hpp"
#include "particle/scene.hpp"

namespace particle::detail {

// sqrt(sum of v^2) over every particle as 2^exp2 * mantissa without overflow or underflow: it
// bounds every speed the particles can reach (collisions conserve energy, walls flip signs).
struct SpeedBound {
  int exp2 = 0;       // ilogb of the largest velocity component; 0 when all are zero
  double scaled = 0;  // sqrt(sum of (v / 2^exp2)^2), in [1, sqrt(2n)] unless all are zero
  double sum_sq = 0;  // sum of (v / 2^exp2)^2
  double log2() const { return scaled > 0 ? exp2 + std::log2(scaled) : -INFINITY; }
};
SpeedBound speed_bound(const Particles& p);

// n particles all at speed v, moving along one axis: what speed_bound() gives for such a scene.
SpeedBound uniform_speed_bound(std::int64_t n, double v);

// check_representable's rules for a scene of box L, radius r and that speed bound, at K =
// slow_factor: the field ("r", "speed" or "energy") and the problem, if any.
std::optional<LimitBreach> representable_breach(double L, double r, const SpeedBound& speed,
                                                int slow_factor);

// log2 of how many times a particle at that speed bound crosses the box (L - 2r) in `steps` time
// units: box_crossings (particle/limits.hpp) without overflow. Infinite where L = 2r and
// something moves, -infinity where nothing moves or S = 0.
double box_crossings_log2(double L, double r, const SpeedBound& speed, std::int64_t steps);

// The continuous-time engine's limits for such a run (box crossings at most kMaxEventCrossings;
// a moving particle in a box of L = 2r; positions resolved to kMaxEventBlur contact distances):
// the field ("r" or "speed") and the problem, if any.
std::optional<LimitBreach> event_work_breach(double L, double r, const SpeedBound& speed,
                                             std::int64_t steps);

// check_representable (particle/limits.hpp) with the scene's speed_bound() already computed:
// simulate() needs it for the length unit too, and a pass over a million speeds costs ~3 ms.
void check_representable(const Scene& scene, const SpeedBound& speed, int slow_factor,
                         const std::string& source, bool continuous_time);

// sum of (vx / 2^exp2)^2 + (vy / 2^exp2)^2. Halving each term would give the same bits (exact
// scaling), so half of it, times 2^(2 exp2), is the plain sum of (vx^2 + vy^2) / 2 wherever that
// sum neither overflows nor underflows.
double scaled_sum_sq(const Particles& p, int exp2);

// k such that lengths are multiplied by 2^k inside the engine: centres ilogb(s) and ilogb(M),
// M = max(L, speed bound / K).
int length_exponent(double L, double s, const SpeedBound& speed, int slow_factor);

// to[i] = from[i] * 2^k, bit for bit std::ldexp (exact while the results are normal doubles);
// from == to is allowed.
void scale_lengths(const double* from, double* to, std::size_t n, int k);
// x *= 2^k for every element.
void scale_lengths(double* values, std::size_t n, int k);

// The displacements per sub-step of p's velocities, in lengths times 2^unit: u = v * 2^unit / K,
// exact (K is a power of two). simulate() and the benchmarks set up their working state with it.
void to_displacements(const Particles& p, int unit, int slow_factor, std::vector<double>& ux,
                      std::vector<double>& uy);

}  // namespace particle::detail
