#pragma once
// The sub-step pipeline, shared by every discrete engine: broad phase, narrow phase (pair and
// wall candidates), order, filter, resolve, advance. Engines differ only in the broad phase, a
// template parameter, so the per-pair code is inlined and never a virtual call.
//
// Threads: one OpenMP parallel region for the whole run. Candidates go to per-thread buffers; one
// thread orders and filters them (the order is total, so the split between threads cannot change
// the result): bit-identical for every thread count.
#include <omp.h>
#include <sched.h>

#include <chrono>
#include <concepts>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "particle/profile.hpp"
#include "stages.hpp"
#include "world.hpp"

namespace particle::detail {

// A broad phase: prepare() builds its structure for the current state (team; ends with a
// barrier if it shares anything), find_pairs() feeds every pair that may collide in this
// sub-step to the narrow phase (team; no barrier needed). It may report more pairs than
// collide, never fewer. name() is the engine that ran, for the metrics.
template <class B>
concept BroadPhase = requires(B& b, const World& w, ThreadScratch& out) {
  b.prepare(w);
  b.find_pairs(w, out);
  { b.name() } -> std::convertible_to<std::string>;
};

struct PipelineParams {
  std::int64_t steps = 0;
  int slow_factor = 1;
  int threads = 1;
  bool profile = false;
  std::function<void(std::int64_t)> on_time_unit;  // called after time units 1..S-1, if set
};

class Stopwatch {
 public:
  Stopwatch() : last_(Clock::now()) {}
  // Adds the time since the previous lap to `stage`.
  void lap(double& stage) {
    const auto now = Clock::now();
    stage += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point last_;
};

template <BroadPhase Broad>
RunReport run_pipeline(Broad& broad, const World& w, const PipelineParams& params) {
  RunReport report;
  report.threads = params.threads;
  report.cpus.assign(params.threads, -1);
  std::vector<ThreadScratch> scratch(params.threads);
  std::vector<Candidate> uncontested, contested, accepted;
  std::vector<std::uint8_t> taken(w.n, 0), uses(w.n, 0);
  StageTimes& st = report.stages;
  const bool profile = params.profile;
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;

#pragma omp parallel num_threads(params.threads)
  {
    ThreadScratch& mine = scratch[omp_get_thread_num()];
    for (std::int64_t step = 1; step <= params.steps; ++step) {
      for (int sub = 0; sub < params.slow_factor; ++sub) {
        broad.prepare(w);
#pragma omp master
        if (profile) watch.lap(st.broad_phase_s);
        mine.candidates.clear();
        find_wall_candidates(w, mine);
        broad.find_pairs(w, mine);
        if (profile) {
#pragma omp barrier
#pragma omp master
          watch.lap(st.narrow_phase_s);
        }
#pragma omp barrier
#pragma omp master
        {
          split_contested(scratch, uses, uncontested, contested);
          if (profile) watch.lap(st.order_s);
          filter_candidates(contested, taken, accepted);
          accept_uncontested(uncontested, taken, accepted);
          if (profile) watch.lap(st.filter_s);
          const std::size_t candidates = uncontested.size() + contested.size();
          report.counters.candidates += candidates;
          report.counters.dropped += candidates - accepted.size();
        }
#pragma omp barrier
        resolve_collisions(w, accepted);
        if (profile) {
#pragma omp barrier
#pragma omp master
          watch.lap(st.resolve_s);
        }
        advance_free(w, taken);
#pragma omp master
        if (profile) watch.lap(st.advance_s);
      }
      if (params.on_time_unit && step < params.steps) {
#pragma omp master
        {
          watch.lap(unused_s);
          params.on_time_unit(step);
          watch.lap(output_s);  // printing is not simulation: kept out of wall_s and the stages
        }
#pragma omp barrier
      }
    }
    report.cpus[omp_get_thread_num()] = sched_getcpu();
  }
  total.lap(report.wall_s);
  report.wall_s -= output_s;

  for (const ThreadScratch& s : scratch) {
    report.counters.pair_tests += s.pair_tests;
    report.counters.overlaps += s.overlaps;
  }
  for (std::size_t i = 0; i < w.n; ++i) {
    report.counters.pair_collisions += w.pair_collisions[i];
    report.counters.wall_collisions += w.wall_collisions[i];
  }
  report.counters.pair_collisions /= 2;  // each pair collision counts on both particles
  report.engine = broad.name();
  return report;
}

}  // namespace particle::detail
