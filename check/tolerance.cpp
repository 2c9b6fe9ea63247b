#include "tolerance.hpp"

#include <algorithm>
#include <cmath>

namespace particle::check {

Tolerance::Tolerance(const Scene& scene, const Particles& start, bool exact_start)
    : in_(exact_start ? 0 : kPrintRounding), s_(scene.contact_distance()) {
  vmax_ = 0;
  for (std::size_t i = 0; i < start.size(); ++i)
    vmax_ = std::max(vmax_, std::hypot(start.vx[i], start.vy[i]));
  const double arith = kArithmetic * std::max(scene.L, vmax_);
  base_ = kPrintRounding + 2 * in_ + arith;
  sep_ = 4 * std::sqrt(2.0) * in_ + arith;
}

double Tolerance::of(const Particles& start, const Particles& result, std::size_t i) const {
  const std::uint64_t pairs = result.pair_collisions[i];
  if (pairs == 0) return base_;
  const double dv = std::hypot(result.vx[i] - start.vx[i], result.vy[i] - start.vy[i]);
  const double w = std::hypot(start.vx[i], start.vy[i]) + vmax_;
  const double gain = 1 + 2 * w * (1 + w / dv) / s_;
  const double bound = base_ + sep_ * std::pow(gain, static_cast<double>(pairs));
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
