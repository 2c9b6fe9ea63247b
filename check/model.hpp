#pragma once
// The reference model for one time unit, always the engine's own code: simulate() for the
// verdicts, and the sub-step stages one by one (candidates, order, filter, resolve, advance) where
// a step has to be explained or altered (diagnosis.hpp). Nothing here redoes the model's
// arithmetic.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "particle/particles.hpp"
#include "particle/scene.hpp"
#include "world.hpp"

namespace particle::check {

// The model's state one time unit after `start` (scene units), by simulate() on one thread; its
// pair_collisions and wall_collisions hold the collisions of that time unit alone.
Particles model_step(const Scene& scene, const Particles& start, int slow_factor);

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

// The candidates of one sub-step, ordered by the model's key, and the ones it accepts.
struct SubStep {
  std::vector<detail::Candidate> ordered, accepted;
};

// Particle i's collision among a sub-step's accepted ones, or nullptr (they share no particle).
const detail::Candidate* collision_of(const std::vector<detail::Candidate>& accepted,
                                      std::uint32_t i);

// Changes sub-step k's accepted collisions (given its ordered candidates) before they are
// resolved: how the diagnosis asks "what if the program did this instead".
using Alteration = std::function<void(int k, const std::vector<detail::Candidate>& ordered,
                                      std::vector<detail::Candidate>& accepted)>;

// One time unit through the stages on all pairs (O(N^2): for explaining a few steps, not for
// checking them all). `record`, if given, gets every sub-step's candidates; the events of
// `accepted` read through event().
class StageStep {
 public:
  StageStep(const Scene& scene, const Particles& start, int slow_factor);
  Particles run(const Alteration& alter = {}, std::vector<SubStep>* record = nullptr) const;
  Event event(int k, const detail::Candidate& c) const;

 private:
  // The K sub-steps on `w`, in the engine's length unit.
  void stages(const detail::World& w, const Alteration& alter, std::vector<SubStep>* record) const;
  const Scene& scene_;
  const Particles& start_;
  int slow_factor_;
};

}  // namespace particle::check
