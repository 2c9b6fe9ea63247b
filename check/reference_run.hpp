#pragma once
// The reference run from the scene, one time unit at a time, as the exact comparison follows the
// output (judge.cpp). simulate() runs a few time units at a time and the observer keeps each
// one's state: the run's set-up, and the sweep's order that a run keeps from one step to the
// next, are paid once a chunk instead of once a time unit (N = 1000, S = 1000, one thread: 120 to
// 140 ms a time unit at a time, 100 ms in chunks or in one run). The chunk doubles from 1 up to
// 64 time units, or fewer where the states would hold more than 64 MiB: a reading that leaves
// the reference at once runs one time unit, and one that follows it wastes at most the rest of a
// chunk. The states are those of step_time_unit() chained, bit for bit (the engine's unit changes
// are exact powers of two: docs/check.md, "Print mode, step by step").
#include <cstddef>
#include <cstdint>
#include <vector>

#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"

namespace particle::check {

class ReferenceRun {
 public:
  ReferenceRun(const Scene& scene, const StepRules& rules);

  // The state one time unit after the last one returned (the first: after the scene's), its
  // collision counts those of that time unit alone. Valid until the next call.
  const Particles& next();

 private:
  void run_chunk();

  const Scene& scene_;
  StepRules rules_;
  Particles last_;                 // the state the next chunk starts from
  std::vector<Particles> states_;  // the chunk's, in order
  std::size_t at_ = 0;             // the next of states_ to return
  std::int64_t done_ = 0;          // time units run so far
  std::int64_t chunk_ = 0;         // time units in the last chunk
};

}  // namespace particle::check
