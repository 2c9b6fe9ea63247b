#pragma once
// The contact laws, the one source of the model's arithmetic (docs/model.md, "The model"): when a
// centre reaches a wall line, when two disks touch, how a collision is resolved and how a free
// particle moves. The discrete pipeline, the event engine and the GPU engine all call these, so
// all compute the same physics with the same operations in the same order; PARTICLE_HD compiles
// them for the GPU too (host_device.hpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "host_device.hpp"
#include "world.hpp"

namespace particle::detail {

struct PairTerms {
  double b, c, disc;
};

// d = p_j - p_i, w = u_j - u_i. disc uses Lagrange's identity a*s^2 - (d x w)^2 instead of
// b^2 - a*c, which would cancel the large |d|^2 |w|^2 terms. Swapping i and j negates d and w,
// which leaves b, c and disc bit-identical: a pair may be passed in either order.  (FLOPS: 15)
PARTICLE_HD inline PairTerms pair_terms(double dx, double dy, double wx, double wy, double s2) {
  const double b = dx * wx + dy * wy;
  const double c = dx * dx + dy * dy - s2;
  const double cross = dx * wy - dy * wx;
  const double disc = (wx * wx + wy * wy) * s2 - cross * cross;
  return {b, c, disc};
}

// The time of contact from now, in the units of w, if the pair ever meets on straight lines:
// approaching and overlapping collide at t = 0; receding (even overlapping) or grazing never
// (infinity); otherwise the smaller root in its stable form c / (-b + sqrt(disc)). The one root
// arithmetic of the lab: the discrete engines bound it to the sub-step (pair_time), the event
// engine does not. Selects instead of branches: the event engine tests every neighbour, and
// whether a pair meets is a coin toss to a branch predictor. (The root of a pair that does not
// meet is computed and dropped; max keeps sqrt off negative numbers, which would set errno
// through a library call.)
PARTICLE_HD inline double contact_time(const PairTerms& p) {
  const double root = p.c / (-p.b + std::sqrt(std::max(p.disc, 0.0)));
  const double t = p.c <= 0 ? 0.0 : (p.disc > 0 ? root : std::numeric_limits<double>::infinity());
  return p.b < 0 ? t : std::numeric_limits<double>::infinity();
}

// The time of contact within the sub-step, if any; touching at t = 1 counts.
PARTICLE_HD inline bool pair_time(const PairTerms& p, double& t) {
  t = contact_time(p);
  return t <= 1;
}

// How deep a pair with c = |d|^2 - s^2 < 0 overlaps, (s - |d|) / s.
PARTICLE_HD inline double overlap_depth(double c, double s2) { return 1 - std::sqrt(1 + c / s2); }

// Time for a centre at x moving at u (per whatever unit u is in) to reach its wall line, lo or
// hi; a negative time (at or past the line, moving out) becomes 0: it hits now. u == 0 never hits
// (the 0/0 or x/0 is discarded by a select, so vector loops stay branch-free). The test is
// |u| > 0, not u != 0 (the same for the finite velocities a scene holds): GCC turns `u != 0 ? t`
// into a branch around the division, which blocks vectorization without AVX-512 masks (with
// AVX2 the wall pass ran scalar, with a mispredicted branch per particle: 17% of the
// million-particle loop).
PARTICLE_HD inline double wall_axis_time(double x, double u, double lo, double hi) {
  const double t = std::max(0.0, ((u > 0 ? hi : lo) - x) / u);
  return std::fabs(u) > 0 ? t : std::numeric_limits<double>::infinity();
}

// Which wall a centre reaches first from its two axis times: the earlier axis, or both (a corner,
// both components flip) when the times are equal. Codes as in world.hpp.
PARTICLE_HD inline std::uint32_t wall_kind(double tx, double ty) {
  return tx < ty ? kWallX : (ty < tx ? kWallY : kWallCorner);
}

// A wall collision of `kind` (world.hpp's codes; a corner hits both walls): flips the velocity
// components normal to the walls hit and returns the momentum the walls received, the sum of
// 2 |u_normal| over them (unit mass, in u's units).
PARTICLE_HD inline double bounce_off_wall(std::uint32_t kind, double& ux, double& uy) {
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
// (FLOPS: 16 and a square root)
PARTICLE_HD inline void exchange_along_normal(double dx, double dy, double& uxi, double& uyi,
                                              double& uxj, double& uyj) {
  double dist = std::sqrt(dx * dx + dy * dy);
  if (dist == 0) {
    // Two centres rounded to one point: in a box whose coordinates are coarser than the contact
    // distance (L/2r beyond 2^52; fuzz_scene found NaN so at L = 4e24, r = 1, K = 4) the normal
    // is lost. They meet head-on along their approach instead, so the state stays finite and
    // the energy kept; every engine calls this function, so they still agree bit for bit.
    dx = uxi - uxj;
    dy = uyi - uyj;
    dist = std::sqrt(dx * dx + dy * dy);
    if (dist == 0) return;  // not approaching: nothing to exchange
  }
  const double nx = dx / dist, ny = dy / dist;
  const double exchange = (uxi - uxj) * nx + (uyi - uyj) * ny;
  uxi -= exchange * nx;
  uyi -= exchange * ny;
  uxj += exchange * nx;
  uyj += exchange * ny;
}

// Moves one coordinate by u * t and keeps it on the wall line if the move would cross it: the
// model's "stops just next to the wall"; only rounding reaches past a line otherwise.
PARTICLE_HD inline double clamped(double moved, double lo, double hi) {
  return moved < lo ? lo : (moved > hi ? hi : moved);
}
PARTICLE_HD inline double move_clamped(double x, double u, double t, double lo, double hi) {
  return clamped(x + u * t, lo, hi);
}

// Moves slot i, at (x, y) after its collision, for the `rest` of the sub-step without crossing a
// wall line (it collides with that wall in the next sub-step: "stops just next to the wall").
// Per coordinate, the crossing coordinate stops on the line and the other moves on; whole
// motion, both stop where the path first meets a line (the 2019 authors' reading). Returns
// whether a line cut the rest short: only then can the two readings part (psim check shares one
// reference run between them until one does: check/reference_run.hpp).
// The line times (two divisions) are computed only where the move ends within `near` of a line:
// from (x, y) in the box to an end inside the box by more than that, the path crosses no line,
// and its times exceed the rest by far more than their rounding ((hi - x) / u is rounded twice,
// 2^-52 of it at most, and hi - x <= hi).
PARTICLE_HD inline bool move_rest(const World& w, std::uint32_t i, double x, double y,
                                  double rest) {
  const double ux = w.ux[i], uy = w.uy[i];
  double to_x = x + ux * rest, to_y = y + uy * rest;
  const double near = w.hi * 0x1p-40;
  bool cut = false;
  if (to_x < w.lo + near || to_x > w.hi - near || to_y < w.lo + near || to_y > w.hi - near) {
    const double stop =
        std::min(wall_axis_time(x, ux, w.lo, w.hi), wall_axis_time(y, uy, w.lo, w.hi));
    cut = stop < rest;
    if (w.whole_motion && cut) {
      to_x = x + ux * stop;
      to_y = y + uy * stop;
    }
  }
  w.x[i] = clamped(to_x, w.lo, w.hi);
  w.y[i] = clamped(to_y, w.lo, w.hi);
  return cut;
}

// Which of a collision's particles a wall line stopped (resolve_collision): bit 0 for c.i, bit 1
// for c.j.
inline constexpr unsigned kStoppedI = 1, kStoppedJ = 2;

// How many particles those bits name.
PARTICLE_HD inline unsigned stopped_count(unsigned stopped) {
  return (stopped & kStoppedI) + (stopped >> 1);
}

// Resolves an accepted collision: moves its particles to time t, applies it, then moves them for
// the rest of the sub-step (move_rest). A pair exchanges the velocity components along the unit
// normal of its actual separation. Accepted collisions share no particle: any order, any split.
// Returns the particles a wall line stopped (kStoppedI, kStoppedJ).
PARTICLE_HD inline unsigned resolve_collision(const World& w, const Candidate& c) {
  const std::uint32_t i = c.i;
  const double xi = move_clamped(w.x[i], w.ux[i], c.t, w.lo, w.hi);
  const double yi = move_clamped(w.y[i], w.uy[i], c.t, w.lo, w.hi);
  const double rest = 1 - c.t;
  if (is_wall(c)) {
    w.wall_impulse[i] += bounce_off_wall(c.j, w.ux[i], w.uy[i]);
    ++w.wall_collisions[i];
    return move_rest(w, i, xi, yi, rest) ? kStoppedI : 0;
  }
  const std::uint32_t j = c.j;
  const double xj = move_clamped(w.x[j], w.ux[j], c.t, w.lo, w.hi);
  const double yj = move_clamped(w.y[j], w.uy[j], c.t, w.lo, w.hi);
  exchange_along_normal(xj - xi, yj - yi, w.ux[i], w.uy[i], w.ux[j], w.uy[j]);
  ++w.pair_collisions[i];
  ++w.pair_collisions[j];
  const bool stopped_i = move_rest(w, i, xi, yi, rest);
  return (stopped_i ? kStoppedI : 0) | (move_rest(w, j, xj, yj, rest) ? kStoppedJ : 0);
}

// Moves particle i, which has no collision this sub-step, by its full displacement, clamped to
// [r, L-r] (only rounding can reach past a wall line, since a real crossing is a candidate).
PARTICLE_HD inline void advance_particle(const World& w, std::size_t i) {
  w.x[i] = move_clamped(w.x[i], w.ux[i], 1, w.lo, w.hi);
  w.y[i] = move_clamped(w.y[i], w.uy[i], 1, w.lo, w.hi);
}

}  // namespace particle::detail
