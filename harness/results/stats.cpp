#include "results/stats.hpp"

#include <algorithm>
#include <cassert>

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
    if (r.ok && r.wall_s)
      walls.push_back(*r.wall_s);
    else
      ++s.failed;
  }
  s.reps = static_cast<int>(walls.size());
  if (!walls.empty()) {
    s.wall_min = minimum(walls);
    s.wall_median = median(walls);
    s.wall_max = maximum(walls);
  }
  return s;
}

}  // namespace psweep
