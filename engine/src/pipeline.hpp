#pragma once
// The sub-step pipeline, shared by every discrete engine: broad phase, narrow phase (pair and
// wall candidates), order, filter, resolve, advance. Engines differ only in the broad phase, a
// template parameter, so the per-pair code is inlined and never a virtual call.
//
// Threads: one OpenMP parallel region for the whole run. Candidates go to per-thread buffers;
// every thread then orders and filters all of them itself (the order is total, so each gets the
// same accepted set whatever the split) and applies the collisions and free moves: to its own
// copy of the state below kPrivateStateBelow particles (one barrier per sub-step, see
// private_state.hpp), else to its share of the shared state (two). The candidate loops hand out
// dynamic chunks, so a thread that is late (descheduled, or sharing a core) leaves its chunks to
// the others. Bit-identical for every thread count.
//
// Profiling adds no synchronisation: the master thread reads the clock between its own stages,
// so narrow_phase_s includes waiting for the last thread's candidates.
#include <omp.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "particle/profile.hpp"
#include "private_state.hpp"
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
  const std::atomic<bool>* stop = nullptr;         // RunOptions::stop
};

// One relaxed load: a signal handler sets the flag, and the engines read it once per sub-step or
// event, so it costs nothing measurable.
inline bool stop_requested(const std::atomic<bool>* stop) {
  return stop && stop->load(std::memory_order_relaxed);
}

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
RunReport run_pipeline(Broad& broad, const World& shared, const PipelineParams& params) {
  const int threads = params.threads;
  const bool private_state = uses_private_state(shared.n);
  RunReport report;
  report.threads = threads;
  report.cpus.assign(threads, -1);
  // Candidates of sub-step k go to scratch[(k % 2) * threads + t]: with one barrier per sub-step a
  // thread may write the next sub-step's candidates while another still selects from these.
  std::vector<ThreadScratch> scratch(2 * static_cast<std::size_t>(threads));
  std::vector<Selection> selections(threads);
  std::vector<StateCopy> copies(private_state ? threads : 0);
  StageTimes& st = report.stages;
  const bool profile = params.profile;
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;
  // A stop request as the master read it at the start of sub-step k, in stop_seen[k % 2]: every
  // thread reads it after the sub-step's barrier, so all leave after the same sub-step. Two
  // slots, because with one barrier per sub-step the master may start sub-step k + 1 (and write
  // its slot) while another thread still reads sub-step k's.
  bool stop_seen[2] = {false, false};
  std::int64_t substeps_done = 0;

#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const bool master = t == 0;
    const World w = private_state ? copies[t].copy_of(shared) : shared;
    Selection& mine = selections[t];
    mine.uses.assign(w.n, 0);
    mine.taken.assign(w.n, 0);
    // The particles this thread moves: all of its private copy, or its share of the shared state.
    const std::size_t first = private_state ? 0 : w.n * t / threads;
    const std::size_t last = private_state ? w.n : w.n * (t + 1) / threads;
    int parity = 0;
    bool stopping = false;
    for (std::int64_t step = 1; step <= params.steps && !stopping; ++step) {
      for (int sub = 0; sub < params.slow_factor && !stopping; ++sub, parity ^= 1) {
        if (master) stop_seen[parity] = stop_requested(params.stop);
        broad.prepare(w);
        if (profile && master) watch.lap(st.broad_phase_s);
        ThreadScratch& found = scratch[static_cast<std::size_t>(parity * threads + t)];
        found.candidates.clear();
        find_wall_candidates(w, found);
        broad.find_pairs(w, found);
#pragma omp barrier  // the one barrier of a sub-step in the private state: all candidates are in
        stopping = stop_seen[parity];
        if (profile && master) watch.lap(st.narrow_phase_s);  // up to the last thread's candidates
        split_contested({scratch.data() + parity * threads, static_cast<std::size_t>(threads)},
                        mine.uses, mine.uncontested, mine.contested, w.id);
        if (profile && master) watch.lap(st.order_s);
        filter_candidates(mine.contested, mine.taken, mine.accepted);
        accept_uncontested(mine.uncontested, mine.taken, mine.accepted);
        if (profile && master) watch.lap(st.filter_s);
        if (master) {
          const std::size_t candidates = mine.uncontested.size() + mine.contested.size();
          report.counters.candidates += candidates;
          report.counters.dropped += candidates - mine.accepted.size();
        }
        const std::size_t accepted = mine.accepted.size();
        resolve_collisions(w, mine.accepted, private_state ? 0 : accepted * t / threads,
                           private_state ? accepted : accepted * (t + 1) / threads);
        if (profile && master) watch.lap(st.resolve_s);
        advance_free(w, mine.taken, first, last);
        release_taken(mine.accepted, mine.taken);
        if (!private_state) {
#pragma omp barrier  // the shared state: every move is done before anyone reads it again
        }
        if (profile && master) watch.lap(st.advance_s);
        if (master) ++substeps_done;
      }
      if (params.on_time_unit && step < params.steps && !stopping) {
        if (master) {
          watch.lap(unused_s);
          if (private_state) copies[0].write_to(shared);
          params.on_time_unit(step);
          watch.lap(output_s);  // printing is not simulation: kept out of wall_s and the stages
        }
        if (!private_state) {
#pragma omp barrier  // the shared state must not move while it is printed
        }
      }
    }
    if (private_state && master) copies[0].write_to(shared);  // every copy holds the same state
    report.cpus[t] = sched_getcpu();
  }
  total.lap(report.wall_s);
  report.wall_s -= output_s;
  // Exact: K is a power of two and the count stays far below 2^53. A request seen in the last
  // sub-step ended nothing early.
  report.time_reached = static_cast<double>(substeps_done) / params.slow_factor;
  report.interrupted = substeps_done / params.slow_factor < params.steps;

  for (const ThreadScratch& s : scratch) {
    report.counters.pair_tests += s.pair_tests;
    report.counters.overlaps += s.overlaps;
    report.physics.max_overlap = std::max(report.physics.max_overlap, s.max_overlap);
  }
  for (std::size_t i = 0; i < shared.n; ++i) {
    report.counters.pair_collisions += shared.pair_collisions[i];
    report.counters.wall_collisions += shared.wall_collisions[i];
  }
  report.counters.pair_collisions /= 2;  // each pair collision counts on both particles
  report.engine = broad.name();
  return report;
}

}  // namespace particle::detail
