#pragma once
// How far a correct program's printed state may lie from the model run from its previous printed
// state (docs/check.md, "The tolerance"). The printed values are the program's state rounded to
// 8 decimals, within kPrintRounding of it; one time unit moves that error by the velocity (x + v),
// a wall hit reflects it (an isometry), and only a pair collision amplifies it: the normal is taken
// from the separation at contact, whose error sideways to the normal grows as the approach gets
// more grazing. The bound per particle, to first order, with W = |v_i| + the largest speed (at
// least |v_j - v_i|), dv = |v_i' - v_i| (the normal part of the relative velocity), s = 2r:
//   free or wall: e = out + 2 in + arith
//   pair:         e + sep (1 + 2 W (1 + W / dv) / s) per collision, sep = 4 sqrt(2) in + arith
// in = kPrintRounding (0 for the first time unit, which starts from the scene's own values), out =
// kPrintRounding, arith = 2^-44 max(L, largest speed) for a program whose arithmetic differs (FMA,
// another order of operations). Under the whole-motion reading a collision's rest that meets a
// wall line stops both coordinates where the path meets it, so the error of the coordinate across
// the line moves the stop along it, by |v_along / v_across| (the velocity after the collision,
// which the stop leaves unchanged): a particle that collided and ends on a wall line gets
//   e (1 + |v_along / v_across|)
// (found grading a whole-motion student program: 30 violations of 3e-8 to 2e-7 on the 2019 timing
// scene, each a wall hit then a stop at a shallow angle). Where that first-order bound exceeds
// kLinearLimit * s (a graze), it no longer holds; it is capped there and the step goes to the
// perturbation test.
#include <cstddef>

#include "particle/options.hpp"
#include "particle/particles.hpp"
#include "particle/scene.hpp"

namespace particle::check {

// Half a unit in the 8th decimal: `%.8f` is within this of the value it prints.
inline constexpr double kPrintRounding = 5e-9;
// The program's own arithmetic may differ by this much relative to the scene's largest length or
// speed (2^-44: 256 units in the last place).
inline constexpr double kArithmetic = 0x1p-44;
// Beyond this fraction of the contact distance the linear bound is not trusted.
inline constexpr double kLinearLimit = 1.0 / 64;

class Tolerance {
 public:
  // For the time unit from `start` under the wall-stop `reading`; `exact_start`: start holds the
  // scene's own values (no print rounding to allow for).
  Tolerance(const Scene& scene, const Particles& start, bool exact_start, WallStop reading);
  // For particle i of `result`, the model's state one time unit after `start` (its collision
  // counts those of that time unit).
  double of(const Particles& start, const Particles& result, std::size_t i) const;

 private:
  // Particle i's error `e` moved along the wall line it stopped on (whole-motion reading).
  double stopped(const Particles& result, std::size_t i, double e) const;

  double in_, base_, sep_, s_, vmax_, lo_, hi_;
  bool whole_motion_;
};

// The largest difference of particle i's x, y, vx, vy between two states.
double difference(const Particles& a, const Particles& b, std::size_t i);

}  // namespace particle::check
