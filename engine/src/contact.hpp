#pragma once
// The contact laws shared by the discrete pipeline and the event engine, so both compute the
// same physics with the same arithmetic: when a centre reaches a wall line, and how two equal
// disks exchange momentum. (The pair's time of contact is contact_time in step/narrow_phase.hpp.)
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "world.hpp"

namespace particle::detail {

// Time for a centre at x moving at u (per whatever unit u is in) to reach its wall line, lo or
// hi; a negative time (at or past the line, moving out) becomes 0: it hits now. u == 0 never hits
// (the 0/0 or x/0 is discarded by a select, so vector loops stay branch-free). The test is
// |u| > 0, not u != 0 (the same for the finite velocities a scene holds): GCC turns `u != 0 ? t`
// into a branch around the division, which blocks vectorization without AVX-512 masks (with
// AVX2 the wall pass ran scalar, with a mispredicted branch per particle: 17% of the
// million-particle loop).
inline double wall_axis_time(double x, double u, double lo, double hi) {
  const double t = std::max(0.0, ((u > 0 ? hi : lo) - x) / u);
  return std::fabs(u) > 0 ? t : std::numeric_limits<double>::infinity();
}

// Which wall a centre reaches first from its two axis times: the earlier axis, or both (a corner,
// both components flip) when the times are equal. Codes as in world.hpp.
inline std::uint32_t wall_kind(double tx, double ty) {
  return tx < ty ? kWallX : (ty < tx ? kWallY : kWallCorner);
}

// A wall collision of `kind` (world.hpp's codes; a corner hits both walls): flips the velocity
// components normal to the walls hit and returns the momentum the walls received, the sum of
// 2 |u_normal| over them (unit mass, in u's units).
inline double bounce_off_wall(std::uint32_t kind, double& ux, double& uy) {
  double impulse = 0;
  if (kind != kWallY) {
    impulse += 2 * std::abs(ux);
    ux = -ux;
  }
  if (kind != kWallX) {
    impulse += 2 * std::abs(uy);
    uy = -uy;
  }
  return impulse;
}

// Elastic collision of equal masses: exchanges the velocity components along the unit normal of
// the actual separation (dx, dy) = p_j - p_i, which conserves energy and momentum to rounding.
// (dx, dy) != 0: an approaching pair is never coincident.  (FLOPS: 16 and a square root)
inline void exchange_along_normal(double dx, double dy, double& uxi, double& uyi, double& uxj,
                                  double& uyj) {
  const double dist = std::sqrt(dx * dx + dy * dy);
  const double nx = dx / dist, ny = dy / dist;
  const double exchange = (uxi - uxj) * nx + (uyi - uyj) * ny;
  uxi -= exchange * nx;
  uyi -= exchange * ny;
  uxj += exchange * nx;
  uyj += exchange * ny;
}

}  // namespace particle::detail
