// The engine's length unit (scale.hpp) and the representability check (particle/limits.hpp).
#include "scale.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <optional>

#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"

namespace particle {
namespace detail {

namespace {

// 2^k where it is a normal double: multiplying by it rounds once, std::ldexp's result bit for bit
// (subnormal results included) at a fraction of a library call's ~100 instructions.
std::optional<double> normal_power_of_two(int k) {
  if (k >= DBL_MIN_EXP - 1 && k < DBL_MAX_EXP) return std::ldexp(1.0, k);
  return std::nullopt;
}

}  // namespace

double scaled_sum_sq(const Particles& p, int exp2) {
  double sum = 0;
  if (const std::optional<double> factor = normal_power_of_two(-exp2)) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double vx = p.vx[i] * *factor, vy = p.vy[i] * *factor;
      sum += vx * vx + vy * vy;
    }
  } else {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double vx = std::ldexp(p.vx[i], -exp2), vy = std::ldexp(p.vy[i], -exp2);
      sum += vx * vx + vy * vy;
    }
  }
  return sum;
}

SpeedBound speed_bound(const Particles& p) {
  // The largest |vx| or |vy| in eight independent lanes: one chain of dependent maxima pays their
  // latency twice per particle (2 ms per million, and a run of the 1M-particle scene takes this
  // four times). A NaN never wins, as with std::max, so the lanes give the same value.
  const std::size_t n = p.size();
  double lane[8] = {};
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4)
    for (std::size_t k = 0; k < 4; ++k) {
      const double ax = std::fabs(p.vx[i + k]), ay = std::fabs(p.vy[i + k]);
      lane[k] = ax > lane[k] ? ax : lane[k];
      lane[4 + k] = ay > lane[4 + k] ? ay : lane[4 + k];
    }
  double largest = 0;
  for (; i < n; ++i) largest = std::max({largest, std::fabs(p.vx[i]), std::fabs(p.vy[i])});
  for (const double each : lane) largest = std::max(largest, each);
  SpeedBound b;
  if (largest == 0) return b;
  b.exp2 = std::ilogb(largest);
  b.sum_sq = scaled_sum_sq(p, b.exp2);
  b.scaled = std::sqrt(b.sum_sq);
  return b;
}

SpeedBound uniform_speed_bound(std::int64_t n, double v) {
  SpeedBound b;
  if (n <= 0 || v == 0) return b;
  b.exp2 = std::ilogb(v);
  const double m = std::ldexp(v, -b.exp2);
  b.sum_sq = static_cast<double>(n) * m * m;
  b.scaled = std::sqrt(b.sum_sq);
  return b;
}

int length_exponent(double L, double s, const SpeedBound& speed, int slow_factor) {
  const int per_substep = speed.scaled > 0 ? std::ilogb(speed.scaled) + speed.exp2 -
                                                 std::ilogb(static_cast<double>(slow_factor))
                                           : INT_MIN;
  const int largest = std::max(std::ilogb(L), per_substep);
  return -((std::ilogb(s) + largest) / 2);
}

void scale_lengths(const double* from, double* to, std::size_t n, int k) {
  if (const std::optional<double> factor = normal_power_of_two(k)) {
    for (std::size_t i = 0; i < n; ++i) to[i] = from[i] * *factor;
  } else {
    for (std::size_t i = 0; i < n; ++i) to[i] = std::ldexp(from[i], k);
  }
}

void scale_lengths(double* values, std::size_t n, int k) {
  if (k != 0) scale_lengths(values, values, n, k);
}

void to_displacements(const Particles& p, int unit, int slow_factor, std::vector<double>& ux,
                      std::vector<double>& uy) {
  const int k = unit - std::ilogb(static_cast<double>(slow_factor));
  ux = p.vx;
  uy = p.vy;
  scale_lengths(ux.data(), ux.size(), k);
  scale_lengths(uy.data(), uy.size(), k);
}

}  // namespace detail

namespace {

// 2^v in decimal (v may be far beyond a double's exponent range): "1.2e+161".
std::string power_of_two(double v) {
  const double decimal = v * std::log10(2.0);
  double exponent = std::floor(decimal);
  std::string mantissa = fmt::format("{:.2g}", std::pow(10.0, decimal - exponent));
  if (mantissa == "10") {  // 9.96... rounds up: 1e+301, not 10e+300
    mantissa = "1";
    exponent += 1;
  }
  return fmt::format("{}e{:+.0f}", mantissa, exponent);
}

}  // namespace

std::string width_problem(double L, double r) {
  const double limit_log2 = std::log2(kMaxLengthRatio);
  const double width_log2 = std::log2(L) - std::log2(2 * r);
  if (width_log2 <= limit_log2) return "";
  return fmt::format(
      "the box is L/(2r) = {} contact distances wide, beyond the limit {} (2^506): the pair "
      "test's squared terms would overflow a double in any unit; use a larger r",
      power_of_two(width_log2), power_of_two(limit_log2));
}

std::optional<LimitBreach> detail::representable_breach(double L, double r, const SpeedBound& speed,
                                                        int slow_factor) {
  const double s = 2 * r;
  const double limit_log2 = std::log2(kMaxLengthRatio);
  if (std::string problem = width_problem(L, r); !problem.empty())
    return LimitBreach{"r", std::move(problem)};
  const double step_log2 = speed.log2() - std::log2(static_cast<double>(slow_factor));
  if (step_log2 - std::log2(s) > limit_log2)
    return LimitBreach{
        "speed",
        fmt::format(
            "the particles can reach a speed of {} per time unit (the root of their summed "
            "squared speeds), {} contact distances per sub-step, beyond the limit {} (2^506): the "
            "pair test's squared terms would overflow a double in any unit; lower the speeds or "
            "raise --slow-factor",
            power_of_two(speed.log2()), power_of_two(step_log2 - std::log2(s)),
            power_of_two(limit_log2))};
  // E = sum_sq / 2 * 2^(2 exp2), compared in log2 so that the check itself cannot overflow.
  const double energy_log2 = std::log2(speed.sum_sq / 2) + 2.0 * speed.exp2;
  if (speed.sum_sq > 0 && energy_log2 >= DBL_MAX_EXP)
    return LimitBreach{"energy", fmt::format("the kinetic energy {} is beyond the largest double "
                                             "({:.2g}); lower the speeds",
                                             power_of_two(energy_log2), DBL_MAX)};
  return std::nullopt;
}

double detail::box_crossings_log2(double L, double r, const SpeedBound& speed, std::int64_t steps) {
  if (speed.scaled == 0 || steps == 0) return -INFINITY;
  return speed.log2() + std::log2(static_cast<double>(steps)) - std::log2(L - 2 * r);
}

std::optional<LimitBreach> detail::event_work_breach(double L, double r, const SpeedBound& speed,
                                                     std::int64_t steps) {
  const double crossings_log2 = box_crossings_log2(L, r, speed, steps);
  // L = 2r pins every centre at L/2, and a moving particle meets both wall lines at once, for
  // ever: infinitely many events in no time (found by fuzz_scene as a hang).
  if (crossings_log2 == INFINITY && L - 2 * r == 0)
    return LimitBreach{"r",
                       "with the event engine a moving particle in a box of L = 2r hits both walls "
                       "infinitely often in no time; use a discrete engine"};
  if (crossings_log2 > std::log2(kMaxEventCrossings))
    return LimitBreach{
        "speed",
        fmt::format("with the event engine the fastest particle could cross the box {} times in "
                    "S time units (speed bound sqrt(sum v^2) x S / (L - 2r)), beyond the limit "
                    "2^40 (about 1.1e12) events it can count; use a discrete engine",
                    power_of_two(crossings_log2))};
  if (crossings_log2 == -INFINITY) return std::nullopt;  // no event: nothing to resolve
  // 2^-52 (L + 2 V S) / s in log2, as a sum of two powers of two that cannot overflow.
  const double box_log2 = std::log2(L) - 52;
  const double motion_log2 = 1 + speed.log2() + std::log2(static_cast<double>(steps)) - 52;
  const double larger = std::max(box_log2, motion_log2);
  const double blur_log2 =
      larger + std::log2(1 + std::exp2(-std::fabs(box_log2 - motion_log2))) - std::log2(2 * r);
  if (blur_log2 <= std::log2(kMaxEventBlur)) return std::nullopt;
  // The box alone: a larger r helps; otherwise lower speeds or fewer time units do.
  const bool box_alone = box_log2 - std::log2(2 * r) > std::log2(kMaxEventBlur);
  return LimitBreach{
      box_alone ? "r" : "speed",
      fmt::format("with the event engine positions are resolved only to {} contact distances "
                  "(2^-52 (L + 2 x speed bound x S) / 2r), beyond the limit 2^-10: it cannot "
                  "tell contact from overlap; {}",
                  power_of_two(blur_log2),
                  box_alone ? "use a larger r or a discrete engine"
                            : "lower the speeds or S, or use a discrete engine")};
}

void detail::check_representable(const Scene& scene, const SpeedBound& speed, int slow_factor,
                                 const std::string& source, bool continuous_time) {
  auto breach = representable_breach(scene.L, scene.r, speed, slow_factor);
  if (!breach && continuous_time) breach = event_work_breach(scene.L, scene.r, speed, scene.steps);
  if (breach) throw InputError(fmt::format("{}: {}: {}", source, breach->key, breach->problem));
}

double box_crossings(const Scene& scene) {
  return std::exp2(detail::box_crossings_log2(scene.L, scene.r,
                                              detail::speed_bound(scene.particles), scene.steps));
}

void check_representable(const Scene& scene, int slow_factor, const std::string& source,
                         std::string_view engine) {
  const EngineInfo* info = find_engine_info(engine);
  detail::check_representable(scene, detail::speed_bound(scene.particles), slow_factor, source,
                              info != nullptr && info->continuous_time);
}

}  // namespace particle
