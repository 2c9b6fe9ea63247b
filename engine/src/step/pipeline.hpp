#pragma once
// The sub-step pipeline, shared by every discrete engine: broad phase, narrow phase (pair and
// wall candidates), order, filter, resolve, advance. Engines differ only in the broad phase, a
// template parameter, so the per-pair code is inlined and never a virtual call.
//
// Threads: one OpenMP parallel region for the whole run. Candidates go to per-thread buffers;
// every thread then orders and filters all of them itself (the order is total, so each gets the
// same accepted set whatever the split) and applies the collisions and free moves: to its own
// copy of the state below kPrivateStateBelow particles (one barrier per sub-step, see
// parallel/private_state.hpp), else to its share of the shared state (two). The candidate loops
// hand out dynamic chunks, so a thread that is late (descheduled, or sharing a core) leaves its
// chunks to the others. Below kPrivateStateBelow particles with more threads than the process has
// cores, the relay runs instead (parallel/relay.hpp): no barrier, and the serial stages run once
// per core, not per thread. Bit-identical for every thread count and either way.
//
// Profiling adds no synchronisation: the thread that runs the serial stages (the master, or the
// relay's closer 0) reads the clock between them, so narrow_phase_s includes waiting for the last
// chunk's candidates.
#include <omp.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "parallel/private_state.hpp"
#include "parallel/relay.hpp"
#include "particle/profile.hpp"
#include "particle/wait_policy.hpp"
#include "step/stages.hpp"
#include "world.hpp"

namespace particle::detail {

// A broad phase: prepare() builds its structure for the current state (team; ends with a
// barrier if it shares anything; the relay calls it on a team of one), chunks() says how many
// pieces find_pairs_in() cuts the pair search into, and find_pairs_in(c) feeds every pair of
// piece c that may collide in this sub-step to the narrow phase (any thread, any order, after
// prepare). All pieces together may report more pairs than collide, never fewer. name() is the
// engine that ran, for the metrics.
template <class B>
concept BroadPhase = requires(B& b, const World& w, ThreadScratch& out, std::uint32_t c) {
  b.prepare(w);
  { b.chunks(w) } -> std::convertible_to<std::uint32_t>;
  b.find_pairs_in(w, c, out);
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

// Sums the per-thread counters and the collision counts into the report.
inline void add_counts(RunReport& report, const std::vector<ThreadScratch>& scratch,
                       const World& w) {
  for (const ThreadScratch& s : scratch) {
    report.counters.pair_tests += s.pair_tests;
    report.counters.overlaps += s.overlaps;
    report.physics.max_overlap = std::max(report.physics.max_overlap, s.max_overlap);
  }
  for (std::size_t i = 0; i < w.n; ++i) {
    report.counters.pair_collisions += w.pair_collisions[i];
    report.counters.wall_collisions += w.wall_collisions[i];
  }
  report.counters.pair_collisions /= 2;  // each pair collision counts on both particles
}

// Closes a run's report once the team has left: the loop's time less printing, the time reached
// (exact: K is a power of two and the count stays far below 2^53; a request seen in the last
// sub-step ended nothing early) and the summed counts.
inline void finish_report(RunReport& report, Stopwatch& total, double output_s,
                          std::int64_t substeps_done, const PipelineParams& params,
                          const std::vector<ThreadScratch>& scratch, const World& w,
                          std::string engine) {
  total.lap(report.wall_s);
  report.wall_s -= output_s;
  report.time_reached = static_cast<double>(substeps_done) / params.slow_factor;
  report.interrupted = substeps_done / params.slow_factor < params.steps;
  add_counts(report, scratch, w);
  report.engine = std::move(engine);
}

// A sub-step's collisions from every thread's candidates, into sel.accepted: the contested ones
// ordered and filtered, then the uncontested. lap(stage) closes a stage's time; `counters` (the
// one thread that counts, null for the others) gets the candidates and those dropped.
template <class Lap>
void select_collisions(std::span<const ThreadScratch> found, Selection& sel, const World& w,
                       StageTimes& st, Lap&& lap, Counters* counters) {
  split_contested(found, sel.uses, sel.uncontested, sel.contested, w.id);
  lap(st.order_s);
  filter_candidates(sel.contested, sel.taken, sel.accepted);
  accept_uncontested(sel.uncontested, sel.taken, sel.accepted);
  lap(st.filter_s);
  if (counters) {
    const std::size_t candidates = sel.uncontested.size() + sel.contested.size();
    counters->candidates += candidates;
    counters->dropped += candidates - sel.accepted.size();
  }
}

// How long a relay waiter spins before it yields (and then sleeps, parallel/relay.hpp): not at all
// when the threads wait passively (OMP_WAIT_POLICY=passive: more threads than free cores), about a
// microsecond otherwise.
inline int relay_spins() {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  return policy && std::strcmp(policy, "passive") == 0 ? 0 : 256;
}

// A closer other than 0 that finds itself kLagRounds or more behind the last claimed round in
// kLagsToResign rounds stops closing (parallel/relay.hpp). Measured on the default scene at T = 3,
// 4, 8 on 2 cores (rounds 6 or more behind): none in 9 quiet runs, 650-850 of 1000 beside a busy
// neighbour.
inline constexpr std::uint64_t kLagRounds = ChunkRelay::kRounds / 4;
inline constexpr int kLagsToResign = 32;

// The relay (parallel/relay.hpp), for small scenes with more threads than cores: a round's chunks
// are the broad phase's pieces; each of the `closers` first threads (one per core) runs everything
// else on its own copy of the state and of the broad phase. Closer 0 uses `broad` itself (its
// name() goes into the report) and writes its copy back for the time-unit callback and at the end.
template <BroadPhase Broad>
RunReport run_relay(Broad& broad, const World& shared, const PipelineParams& params, int closers) {
  const int threads = params.threads;
  RunReport report;
  report.threads = threads;
  report.cpus.assign(threads, -1);
  // Round r's candidates from thread t go to scratch[(r % kRounds) * threads + t]
  // (parallel/relay.hpp).
  const std::uint64_t kRounds = ChunkRelay::kRounds;
  std::vector<ThreadScratch> scratch(kRounds * static_cast<std::size_t>(threads));
  std::vector<Broad> copies_of_broad(static_cast<std::size_t>(closers - 1), broad);
  std::vector<Broad*> broads{&broad};
  for (Broad& b : copies_of_broad) broads.push_back(&b);
  std::vector<StateCopy> copies(static_cast<std::size_t>(closers));
  std::vector<World> worlds;
  for (StateCopy& copy : copies) worlds.push_back(copy.copy_of(shared));
  // Set by the opener of round r, in slot r % kRounds, for its chunks and its closing.
  struct Round {
    int source = 0;                 // the closer whose copy the chunks search
    std::uint32_t pair_chunks = 0;  // the broad phase's pieces (a round has at least one chunk)
    bool stop_seen = false;         // a stop request as read when the round opened
  };
  std::vector<Round> rounds(kRounds);
  StageTimes& st = report.stages;
  const bool profile = params.profile;
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;
  const std::uint64_t substeps = static_cast<std::uint64_t>(params.steps * params.slow_factor);
  std::int64_t substeps_done = 0;  // closer 0's
  const auto wall_chunks = static_cast<std::uint32_t>((shared.n + kWallChunk - 1) / kWallChunk);
  ChunkRelay relay(relay_spins(), closers);
  if (substeps == 0) relay.finish();

  const auto search = [&](const ChunkRelay::Ticket& ticket, int copy, int t) {
    const std::uint64_t q = ticket.round % kRounds;
    if (ticket.chunk < rounds[q].pair_chunks)
      broads[copy]->find_pairs_in(worlds[copy], ticket.chunk, scratch[q * threads + t]);
  };

  // A thread that only takes chunks, until the run is finished.
  const auto take_chunks = [&](int t) {
    while (relay.wait_for_work()) {
      ChunkRelay::Ticket ticket;
      if (!relay.take(ticket)) continue;
      search(ticket, rounds[ticket.round % kRounds].source, t);
      relay.finish_chunk();
    }
  };

#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    if (t >= closers) {
      take_chunks(t);
    } else if (substeps > 0) {
      start_on_cpu(t);  // one closer per core (parallel/relay.hpp)
      int lags = 0;     // rounds this closer closed kLagRounds or more behind
      const bool master = t == 0;
      const auto lap = [&](double& stage) {
        if (profile && master) watch.lap(stage);
      };
      const World& w = worlds[static_cast<std::size_t>(t)];
      Broad& own = *broads[static_cast<std::size_t>(t)];
      Selection sel;
      sel.uses.assign(w.n, 0);
      sel.taken.assign(w.n, 0);
      std::uint32_t chunks_so_far = 0;  // of every round up to `round`, modulo 2^32
      // Builds this closer's structure for `round` and opens it if no other closer has.
      const auto prepare = [&](std::uint64_t round) {
#pragma omp parallel num_threads(1)
        own.prepare(w);  // a team of one: no other thread is in a worksharing construct
        lap(st.broad_phase_s);
        const std::uint32_t pieces = own.chunks(w);
        const std::uint32_t chunks = std::max<std::uint32_t>(1, pieces);
        chunks_so_far += chunks;
        if (!relay.claim(round)) return;
        relay.wait_for_selections(round);
        const std::uint64_t q = round % kRounds;
        for (int k = 0; k < threads; ++k) scratch[q * threads + k].candidates.clear();
        rounds[q] = {t, pieces, stop_requested(params.stop)};
        // The opener finds the wall candidates itself: they read the whole state, which it has
        // just written (as chunks, other cores' reads cost more than the pass: 5 us a sub-step).
        ThreadScratch& mine = scratch[q * threads + t];
        for (std::uint32_t c = 0; c < wall_chunks; ++c) find_wall_candidates_in(w, c, mine);
        lap(st.narrow_phase_s);
        relay.open(round, chunks);
      };
      std::uint64_t round = 1;
      prepare(round);
      for (;;) {
        relay.wait_open(round);
        ChunkRelay::Ticket ticket;
        // A closer behind the open round closes its own first (with a busy neighbour on its
        // core it may fall behind); a chunk of a later round taken in a race searches the
        // opener's copy.
        while (relay.open_round() == round && relay.take(ticket)) {
          search(ticket, ticket.round == round ? t : rounds[ticket.round % kRounds].source, t);
          relay.finish_chunk();
        }
        relay.wait_done(chunks_so_far);
        lap(st.narrow_phase_s);  // up to the last chunk's candidates
        const std::uint64_t q = round % kRounds;
        select_collisions({scratch.data() + q * threads, static_cast<std::size_t>(threads)}, sel, w,
                          st, lap, master ? &report.counters : nullptr);
        const bool last = rounds[q].stop_seen || round == substeps;
        relay.selected(t, round);
        if (!master && relay.claimed() >= round + kLagRounds && ++lags == kLagsToResign) {
          relay.resign(t);
          take_chunks(t);
          break;
        }
        resolve_collisions(w, sel.accepted);
        lap(st.resolve_s);
        advance_free(w, sel.taken);
        release_taken(sel.accepted, sel.taken);
        lap(st.advance_s);
        if (master) {
          ++substeps_done;
          const std::int64_t step = substeps_done / params.slow_factor;
          if (params.on_time_unit && !last && substeps_done % params.slow_factor == 0) {
            watch.lap(unused_s);
            copies[0].write_to(shared);
            params.on_time_unit(step);
            watch.lap(output_s);  // printing is not simulation: kept out of wall_s and the stages
          }
        }
        if (last) {
          relay.finish();
          break;
        }
        prepare(++round);
      }
      if (master) copies[0].write_to(shared);
    }
    report.cpus[t] = sched_getcpu();
  }
  finish_report(report, total, output_s, substeps_done, params, scratch, shared, broad.name());
  return report;
}

template <BroadPhase Broad>
RunReport run_pipeline(Broad& broad, const World& shared, const PipelineParams& params) {
  const int threads = params.threads;
  const bool private_state = uses_private_state(shared.n);
  const int cpus = available_cpus();
  if (private_state && threads > cpus) return run_relay(broad, shared, params, cpus);
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
    const auto lap = [&](double& stage) {
      if (profile && master) watch.lap(stage);
    };
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
        lap(st.broad_phase_s);
        ThreadScratch& found = scratch[static_cast<std::size_t>(parity * threads + t)];
        found.candidates.clear();
        find_wall_candidates(w, found);
        find_pairs(broad, w, found);
#pragma omp barrier  // the one barrier of a sub-step in the private state: all candidates are in
        stopping = stop_seen[parity];
        lap(st.narrow_phase_s);  // up to the last thread's candidates
        select_collisions({scratch.data() + parity * threads, static_cast<std::size_t>(threads)},
                          mine, w, st, lap, master ? &report.counters : nullptr);
        const std::size_t accepted = mine.accepted.size();
        resolve_collisions(w, mine.accepted, private_state ? 0 : accepted * t / threads,
                           private_state ? accepted : accepted * (t + 1) / threads);
        lap(st.resolve_s);
        advance_free(w, mine.taken, first, last);
        release_taken(mine.accepted, mine.taken);
        if (!private_state) {
#pragma omp barrier  // the shared state: every move is done before anyone reads it again
        }
        lap(st.advance_s);
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
  finish_report(report, total, output_s, substeps_done, params, scratch, shared, broad.name());
  return report;
}

}  // namespace particle::detail
