#pragma once
// One time unit of a print-mode output against the model: the model run from the program's
// printed state at t-1, compared with its printed state at t within the tolerance
// (tolerance.hpp); a particle beyond it is explained by rounding when the model, run from a start
// moved within the print rounding, gives the program's value (docs/check.md, "Ambiguity").
#include <cstdint>
#include <string>
#include <vector>

#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"

namespace particle::check {

// Starts drawn within the print rounding per time unit in question: half uniform in the box of
// +-kPrintRounding around each printed value, half at its corners (a linear effect is largest
// there).
inline constexpr int kDraws = 16;

struct StepResult {
  Particles model;                         // the model from the printed start (this step's counts)
  std::vector<std::uint32_t> explained;    // beyond the tolerance, explained by rounding
  std::vector<std::uint32_t> unexplained;  // beyond it whatever the start (or not finite)
  double largest_difference = 0;           // of the particles beyond the tolerance
  double largest_tolerance = 0;
  std::string detail;  // how rounding explains the first explained particle
};

// `exact_start`: start is the scene's own values (time unit 1), so no rounding is allowed for.
// `model`: step_time_unit(scene, start, rules), which the readings of a check share where they
// give the same state (SharedChunks::run).
StepResult check_step(const Scene& scene, const StepRules& rules, std::int64_t step,
                      const Particles& start, bool exact_start, const Particles& printed,
                      const Particles& model);

}  // namespace particle::check
