#include "tolerance.hpp"

#include <algorithm>
#include <cmath>

namespace particle::check {

Tolerance::Tolerance(const Scene& scene, const Particles& start, bool exact_start,
                     WallStop reading)
    : in_(exact_start ? 0 : kPrintRounding),
      s_(scene.contact_distance()),
      lo_(scene.r),
      hi_(scene.L - scene.r),
      whole_motion_(reading == WallStop::whole_motion) {
  vmax_ = 0;
  for (std::size_t i = 0; i < start.size(); ++i)
    vmax_ = std::max(vmax_, std::hypot(start.vx[i], start.vy[i]));
  const double arith = kArithmetic * std::max(scene.L, vmax_);
  base_ = kPrintRounding + 2 * in_ + arith;
  sep_ = 4 * std::sqrt(2.0) * in_ + arith;
}

double Tolerance::stopped(const Particles& result, std::size_t i, double e) const {
  if (!whole_motion_ || result.pair_collisions[i] + result.wall_collisions[i] == 0) return e;
  const auto on_line = [&](double v) { return v == lo_ || v == hi_; };
  const double vx = std::fabs(result.vx[i]), vy = std::fabs(result.vy[i]);
  // On both lines (a corner) the stop leaves nothing to move along.
  if (on_line(result.x[i]) == on_line(result.y[i])) return e;
  return e * (1 + (on_line(result.x[i]) ? vy / vx : vx / vy));
}

double Tolerance::of(const Particles& start, const Particles& result, std::size_t i) const {
  const std::uint64_t pairs = result.pair_collisions[i];
  double bound = base_;
  if (pairs > 0) {
    const double dv = std::hypot(result.vx[i] - start.vx[i], result.vy[i] - start.vy[i]);
    const double w = std::hypot(start.vx[i], start.vy[i]) + vmax_;
    const double gain = 1 + 2 * w * (1 + w / dv) / s_;
    bound += sep_ * std::pow(gain, static_cast<double>(pairs));
  }
  bound = stopped(result, i, bound);
  const double cap = std::max(base_, kLinearLimit * s_);
  return std::isfinite(bound) ? std::min(bound, cap) : cap;
}

double difference(const Particles& a, const Particles& b, std::size_t i) {
  double d = 0;
  for (const double e : {a.x[i] - b.x[i], a.y[i] - b.y[i], a.vx[i] - b.vx[i], a.vy[i] - b.vy[i]})
    d = std::isnan(e) ? INFINITY : std::max(d, std::fabs(e));
  return d;
}

}  // namespace particle::check
