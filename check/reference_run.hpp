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
//
// The readings of one check share their runs (SharedChunks): two readings give the same states
// until something happens on which they part (a receding overlap for the overlap readings, a
// collision cut short by a wall line for the wall-stop ones: the engine counts both), so a
// reading whose chunk starts from the state another reading's chunk started from, where nothing
// of the kind happened, takes that chunk's states instead of running it. On a scene where the
// readings never part, four readings cost one run.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"

namespace particle::check {

// The states of time units run from a state: each time unit's, its counts those of that time
// unit alone, or the last alone with the counts of the whole stretch.
using States = std::shared_ptr<const std::vector<Particles>>;

class SharedChunks {
 public:
  // `length` time units of `scene` (its L, r and mode) from `start` under `rules`, on one thread:
  // another reading's states where they are this reading's too, else a run.
  States run(const Scene& scene, const StepRules& rules, const Particles& start,
             std::int64_t length, bool every_unit);

  // Whether the output's time unit `time` prints state `index` of `chunk` (one of run()'s), by
  // compare(): once for all the readings whose reference is that state (the readings are fed
  // each block in turn, so the last answer is the one the next reading asks for).
  template <class Compare>
  bool prints(const States& chunk, std::size_t index, std::int64_t time, Compare&& compare) {
    if (printed_.chunk != chunk || printed_.index != index || printed_.time != time)
      printed_ = {chunk, index, time, compare()};
    return printed_.same;
  }

 private:
  struct Chunk {
    StepRules rules;
    Particles start;
    std::int64_t length = 0;
    bool every_unit = false;
    std::uint64_t receding_overlaps = 0, wall_stops = 0;  // where the readings part
    States states;
  };
  // The last chunk of each reading and layout: what a reading in step with it asks for next.
  std::vector<Chunk> last_;
  struct Printed {
    States chunk;  // held, so that its address names no other states meanwhile
    std::size_t index = 0;
    std::int64_t time = -1;
    bool same = false;
  } printed_;
};

class ReferenceRun {
 public:
  ReferenceRun(const Scene& scene, const StepRules& rules, SharedChunks& shared);

  // The state one time unit after the last one returned (the first: after the scene's), its
  // collision counts those of that time unit alone. Valid until the next call.
  const Particles& next();
  // The chunk and index of the state next() returned last.
  const States& chunk() const { return states_; }
  std::size_t index() const { return at_ - 1; }

 private:
  void run_chunk();

  const Scene& scene_;
  StepRules rules_;
  SharedChunks& shared_;
  Particles last_;         // the state the next chunk starts from
  States states_;          // the chunk's, in order
  std::size_t at_ = 0;     // the next of states_ to return
  std::int64_t done_ = 0;  // time units run so far
  std::int64_t chunk_ = 0; // time units in the last chunk
};

}  // namespace particle::check
