#pragma once
// The model's sub-step stage by stage (candidates, order, filter, resolve, advance), for tools
// that explain a step rather than run it: `psim check` replays a time unit, records each
// sub-step's candidates and asks "what if the program had accepted these instead" by altering a
// sub-step's accepted collisions before they are resolved (check/diagnosis.cpp). It is the
// engine's own code on all pairs, O(N^2) per sub-step: for a few steps, not for running a scene.
#include <cstdint>
#include <functional>
#include <vector>

#include "particle/options.hpp"
#include "particle/particles.hpp"
#include "particle/scene.hpp"

namespace particle {

// A collision candidate of one sub-step: particles i and j meet at fraction t of it. A wall
// candidate has j >= kWallX, and j says which velocity components flip.
struct Candidate {
  double t;  // fraction of the sub-step, in [0, 1]
  std::uint32_t i, j;
};

inline constexpr std::uint32_t kWallX = 0xFFFFFFFDu;
inline constexpr std::uint32_t kWallY = 0xFFFFFFFEu;
inline constexpr std::uint32_t kWallCorner = 0xFFFFFFFFu;
// constexpr: the CUDA engine compiles it for the device too (--expt-relaxed-constexpr).
constexpr bool is_wall(const Candidate& c) { return c.j >= kWallX; }
// Whether particle i is one of the candidate's.
constexpr bool involves(const Candidate& c, std::uint32_t i) {
  return c.i == i || (!is_wall(c) && c.j == i);
}

// The model's filter (docs/model.md): greedy over `ordered`, it accepts a candidate whose
// particles no earlier accepted one holds. Marks taken[i] for every accepted particle; taken must
// be all zero on entry.
void filter_candidates(const std::vector<Candidate>& ordered, std::vector<std::uint8_t>& taken,
                       std::vector<Candidate>& accepted);

// One sub-step's candidates in the model's order, and the ones it accepted (after any alteration).
struct SubStep {
  std::vector<Candidate> ordered, accepted;
};

// Changes sub-step k's accepted collisions, given its ordered candidates, before they are resolved.
using Alteration = std::function<void(int k, const std::vector<Candidate>& ordered,
                                      std::vector<Candidate>& accepted)>;

// What one time unit of the model depends on besides the state: K sub-steps and the readings.
struct StepRules {
  int slow_factor = 1;
  WallStop wall_stop = WallStop::per_coordinate;
  Overlap overlap = Overlap::approaching;
};

// The state one time unit after `start` in `scene` (its L, r and mode) under `rules`, by
// simulate() on one thread. The collision counts are those of this time unit alone.
Particles step_time_unit(const Scene& scene, const Particles& start, const StepRules& rules);

// The same state through the stages one by one (same unit set-up, same stages, so the same
// result) unless `alter` changes a sub-step. `record`, if given, gets every sub-step's candidates.
Particles replay_time_unit(const Scene& scene, const Particles& start, const StepRules& rules,
                           const Alteration& alter = {}, std::vector<SubStep>* record = nullptr);

}  // namespace particle
