#pragma once
// Names what a violation is. For the particles of a time unit that no start within the print
// rounding explains, the model's sub-steps are run through the engine's stages and altered as a
// program that breaks one rule would run them: a collision of the particle left out (a wall hit
// missed, an overlapping approaching pair left alone), a rejected candidate taken instead of the
// accepted one (a pair before a wall on a tie, a pair before an earlier wall hit), or taken as
// well (two collisions for one particle). The first alteration that gives the printed values
// names the kind; without one, the kind says what the model does to the particle there.
#include <cstdint>
#include <vector>

#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"
#include "report.hpp"

namespace particle::check {

struct StepStates {
  std::int64_t step = 0;
  const Particles& start;    // the printed state at step - 1 (or the scene's)
  bool exact_start = false;  // start holds the scene's own values
  const Particles& printed;  // the printed state at step
  const Particles& model;    // step_time_unit() from start
};

// Violations for `particles` (in index order); the first `detailed` are tried against the
// alterations (each costs a few runs of the stages on all pairs), then, for them and with
// `orders` for the others too, against a wrong order of collisions in every sub-step (two runs of
// the stages for the time unit, whatever the number of particles). A particle nothing explains
// gets the kind the model's collision counts say.
std::vector<Violation> diagnose(const Scene& scene, const StepRules& rules,
                                const StepStates& states,
                                const std::vector<std::uint32_t>& particles, std::size_t detailed,
                                bool orders);

}  // namespace particle::check
