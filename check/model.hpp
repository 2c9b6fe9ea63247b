#pragma once
// The reference model for one time unit, always the engine's own code (particle/replay.hpp):
// step_time_unit for the verdicts, and the sub-step stages one by one where a step has to be
// explained or altered (diagnosis.hpp). Nothing here redoes the model's arithmetic.
#include <cstdint>
#include <string>
#include <vector>

#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"

namespace particle::check {

// A collision of the model in scene terms: its particles, the time within the time unit (sub-step
// k of K at fraction t is (k + t) / K), and for a wall which components flip.
struct Event {
  double time = 0;
  std::uint32_t i = 0, j = 0;  // j == i for a wall
  bool wall = false, flips_x = false, flips_y = false;
  bool overlap = false;  // a pair already overlapping at the sub-step's start (t = 0)
};

// "wall hit of particle 3 at t = 0.25 of the step (vx flips)", "pair 1-4 at t = 0.5 of the step".
std::string describe(const Event& e);

// Particle i's collision among a sub-step's accepted ones, or nullptr (they share no particle).
const Candidate* collision_of(const std::vector<Candidate>& accepted, std::uint32_t i);

// One time unit of a scene from `start` through the stages (replay_time_unit), and its
// collisions in scene terms through event().
class StageStep {
 public:
  StageStep(const Scene& scene, const Particles& start, const StepRules& rules);
  Particles run(const Alteration& alter = {}, std::vector<SubStep>* record = nullptr) const;
  Event event(int k, const Candidate& c) const;

 private:
  const Scene& scene_;
  const Particles& start_;
  StepRules rules_;
};

}  // namespace particle::check
