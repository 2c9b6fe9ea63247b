#include "results/stats.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

namespace psweep {

double minimum(const std::vector<double>& v) {
  assert(!v.empty());
  return *std::min_element(v.begin(), v.end());
}

double maximum(const std::vector<double>& v) {
  assert(!v.empty());
  return *std::max_element(v.begin(), v.end());
}

double median(std::vector<double> v) {
  assert(!v.empty());
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return lower + (upper - lower) / 2;
}

Summary summarize(const std::vector<RecordedRun>& runs, const std::string& id) {
  Summary s;
  std::vector<double> walls;
  for (const auto& r : runs) {
    if (r.config_id != id) continue;
    if (r.ok && r.wall_s) {
      if (!s.wall_min || *r.wall_s < *s.wall_min) {  // the fastest so far: its builds
        s.wall_min = r.wall_s;
        s.builds_per_substep = r.builds_per_substep;
      }
      walls.push_back(*r.wall_s);
    } else {
      ++s.failed;
    }
  }
  s.reps = static_cast<int>(walls.size());
  if (!walls.empty()) {
    s.wall_median = median(walls);
    s.wall_max = maximum(walls);
  }
  return s;
}

std::optional<double> builds_per_substep(const std::string& builds, const std::string& time_reached,
                                         std::optional<std::int64_t> slow_factor) {
  double b = 0, t = 0;
  std::size_t used_b = 0, used_t = 0;
  try {
    b = std::stod(builds, &used_b);
    t = std::stod(time_reached, &used_t);
  } catch (const std::logic_error&) {
    return std::nullopt;
  }
  const double substeps = t * static_cast<double>(slow_factor.value_or(1));
  if (used_b != builds.size() || used_t != time_reached.size() || !(substeps > 0))
    return std::nullopt;
  return b / substeps;
}

std::optional<double> state_gb_per_s(double particle_steps, std::optional<double> wall_s) {
  if (!wall_s || !(*wall_s > 0) || !(particle_steps > 0)) return std::nullopt;
  return kStateBytes * particle_steps / *wall_s / 1e9;
}

}  // namespace psweep
