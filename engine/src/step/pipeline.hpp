#pragma once
// The sub-step pipeline, shared by every discrete engine: broad phase, narrow phase (pair and
// wall candidates), order, filter, resolve, advance. Engines differ only in the broad phase, a
// template parameter, so the per-pair code is inlined and never a virtual call.
//
// Threads: one OpenMP parallel region for the whole run. Candidates go to per-thread buffers;
// every thread then orders and filters all of them itself (the order is total, so each gets the
// same accepted set whatever the split) and applies the collisions and free moves: to its own
// copy of the state below kPrivateStateBelow particles (one barrier per sub-step, see
// parallel/private_state.hpp), else to its share of the shared state (two). In the shared state,
// from kTeamSplitFrom candidates a sub-step on, each thread splits its own candidates instead
// and one orders and filters the contested ones (select_over_team, three barriers more). The
// candidate loops hand out dynamic chunks, so a thread that is late (descheduled, or sharing a
// core) leaves its chunks to the others. Below kPrivateStateBelow particles with more threads
// than the process has cores, the relay runs instead (parallel/relay.hpp): no barrier, and the
// serial stages run once per core, not per thread. Bit-identical for every thread count and
// either way.
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
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "parallel/private_state.hpp"
#include "parallel/relay.hpp"
#include "parallel/team.hpp"
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
// engine that ran and builds() how many structures prepare() built (the broad_phase_builds
// metric: thread 0's count, so each build counts once whatever the team), for the metrics.
template <class B>
concept BroadPhase = requires(B& b, const World& w, ThreadScratch& out, std::uint32_t c) {
  b.prepare(w);
  { b.chunks(w) } -> std::convertible_to<std::uint32_t>;
  b.find_pairs_in(w, c, out);
  { b.name() } -> std::convertible_to<std::string>;
  { b.builds() } -> std::convertible_to<std::uint64_t>;
};

struct PipelineParams {
  std::int64_t steps = 0;
  int slow_factor = 1;
  int threads = 1;
  bool profile = false;
  std::function<void(std::int64_t)> on_time_unit;  // called after time units 1..S-1, if set
  const std::atomic<bool>* stop = nullptr;         // RunOptions::stop
  // For an engine that holds the state elsewhere during the run (the mpi engine's ranks, each
  // with its share): release_state frees the run's arrays (the World's and the scene's), and
  // restore_state allocates the World's again and returns the World over them, for the engine
  // to fill before anything reads them (the time-unit callback, the end). Unset: nothing to free.
  std::function<void()> release_state;
  std::function<World()> restore_state;
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
    report.counters.receding_overlaps += s.receding_overlaps;
    report.counters.wall_stops += s.wall_stops;
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
// sub-step ended nothing early), the summed counts, the engine that ran and its broad phase's
// builds.
inline void finish_report(RunReport& report, Stopwatch& total, double output_s,
                          std::int64_t substeps_done, const PipelineParams& params,
                          const std::vector<ThreadScratch>& scratch, const World& w,
                          std::string engine, std::uint64_t builds) {
  total.lap(report.wall_s);
  report.wall_s -= output_s;
  report.time_reached = static_cast<double>(substeps_done) / params.slow_factor;
  report.interrupted = substeps_done / params.slow_factor < params.steps;
  add_counts(report, scratch, w);
  report.counters.broad_phase_builds = builds;
  report.engine = std::move(engine);
}

// The report of a run by `threads` threads, before it runs: each thread's CPU is filled in at the
// end of the team.
inline RunReport team_report(int threads) {
  RunReport report;
  report.threads = threads;
  report.cpus.assign(threads, -1);
  return report;
}

// The time-unit callback, on the state written back from `copy` (null: the shared state is
// current). Printing is not simulation: its time goes to output_s, out of wall_s and the stages.
inline void observe(const PipelineParams& params, std::int64_t step, StateCopy* copy,
                    const World& shared, Stopwatch& watch, double& unused_s, double& output_s) {
  watch.lap(unused_s);
  if (copy) copy->write_to(shared);
  params.on_time_unit(step);
  watch.lap(output_s);
}

// A sub-step's collisions from every thread's candidates, into sel.accepted: the contested ones
// ordered and filtered, then the uncontested. lap(stage) closes a stage's time; `counters` (the
// one thread that counts, null for the others) gets the candidates and those dropped.
template <class Lap>
void select_collisions(std::span<const ThreadScratch> found, Selection& sel, const World& w,
                       StageTimes& st, Lap&& lap, Counters* counters) {
  split_contested(found, w.overlaps_collide, sel.uses, sel.uncontested, sel.contested, w.id);
  lap(st.order_s);
  filter_candidates(sel.contested, sel.taken, sel.accepted);
  accept_uncontested(sel.uncontested, sel.taken, sel.accepted);
  lap(st.filter_s);
  if (counters) {
    const std::size_t candidates = sel.uncontested.size() + sel.contested.size();
    counters->candidates += candidates;
    counters->dropped += candidates - sel.accepted.size();
    for (const auto* list : {&sel.uncontested, &sel.contested})
      for (const Candidate& c : *list) counters->pair_candidates += !is_wall(c);
  }
}

// Candidates of a sub-step from which the shared state's threads split its selection
// (select_over_team) rather than each selecting from all of them. Measured at T = 2 on a 2-core
// VM: the million-particle scene (30,000 a sub-step) and N = 100,000 of its kind (3,000) gained
// from the split, the slow crowd (N = 20,000, about 200) lost 12% of its loop to the barriers.
inline constexpr std::size_t kTeamSplitFrom = 2048;

// The runs' candidates, the receding overlapping pairs among them where they collide.
inline std::size_t candidate_count(std::span<const ThreadScratch> runs, bool with_receding) {
  std::size_t n = 0;
  for (const ThreadScratch& run : runs)
    n += run.candidates.size() + (with_receding ? run.receding.size() : 0);
  return n;
}

// team, barriers inside and at the end: select_collisions split over the team. Thread t splits
// its own candidates (runs[t]) into selections[t]'s lists and accepts its uncontested ones
// (marked in sel.taken; resolving them is its own), then one thread orders and filters every
// thread's contested ones into sel.accepted. The accepted set is select_collisions's.
template <class Lap>
void select_over_team(std::span<const ThreadScratch> runs, int t,
                      std::vector<Selection>& selections, Selection& sel, const World& w,
                      StageTimes& st, Lap&& lap, Counters* counters) {
  Selection& mine = selections[static_cast<std::size_t>(t)];
  split_own_contested(runs, selections, t, w.overlaps_collide, w.id);
  for (const Candidate& c : mine.uncontested) {
    sel.taken[c.i] = 1;
    if (!is_wall(c)) sel.taken[c.j] = 1;
  }
  team_single([&] {
    sel.contested.clear();
    for (const Selection& s : selections)
      sel.contested.insert(sel.contested.end(), s.contested.begin(), s.contested.end());
    order_candidates(sel.contested, w.id);
    lap(st.order_s);
    filter_candidates(sel.contested, sel.taken, sel.accepted);
    lap(st.filter_s);
    if (counters) {
      std::size_t accepted = sel.accepted.size();
      for (const Selection& s : selections) accepted += s.uncontested.size();
      const std::size_t candidates = candidate_count(runs, w.overlaps_collide);
      counters->candidates += candidates;
      counters->dropped += candidates - accepted;
      for (const ThreadScratch& run : runs) {
        for (const Candidate& c : run.candidates) counters->pair_candidates += !is_wall(c);
        if (w.overlaps_collide) counters->pair_candidates += run.receding.size();
      }
    }
  });
}

// The team pipeline's collisions of a sub-step, once its candidates are in: selected (each thread
// from all of them, or split over the team: select_over_team), resolved, and the free particles
// advanced, by each thread its share (all of them in a private copy).
class SubstepCollisions {
 public:
  SubstepCollisions(int threads, bool private_state, std::size_t n)
      : threads_(threads), private_state_(private_state), selections_(threads) {
    if (!private_state && threads > 1) team_selection_.taken.assign(n, 0);
  }

  // Thread t, before its first sub-step: its own marks, first touched by it.
  void start(int t, std::size_t n) {
    selections_[t].uses.assign(n, 0);
    selections_[t].taken.assign(n, 0);
  }

  // team (barriers inside in the shared state, one at the end): thread t's part of the sub-step
  // whose candidates are `runs`, moving particles [first, last) of w; wall stops go to `found`,
  // the counts to `counters` (the one thread that counts, null for the others).
  template <class Lap>
  void apply(int t, std::span<const ThreadScratch> runs, const World& w, std::size_t first,
             std::size_t last, ThreadScratch& found, StageTimes& st, Lap&& lap,
             Counters* counters) {
    Selection& mine = selections_[t];
    const bool split = !private_state_ && threads_ > 1 &&
                       candidate_count(runs, w.overlaps_collide) >= kTeamSplitFrom;
    Selection& sel = split ? team_selection_ : mine;
    std::uint64_t stopped = 0;
    if (split) {
      select_over_team(runs, t, selections_, team_selection_, w, st, lap, counters);
      stopped = resolve_collisions(w, mine.uncontested);
    } else {
      select_collisions(runs, mine, w, st, lap, counters);
    }
    const std::size_t accepted = sel.accepted.size();
    stopped += resolve_collisions(w, sel.accepted, private_state_ ? 0 : accepted * t / threads_,
                                  private_state_ ? accepted : accepted * (t + 1) / threads_);
    if (t == 0 || !private_state_) found.wall_stops += stopped;  // private: each resolves all
    lap(st.resolve_s);
    advance_free(w, sel.taken, first, last, private_state_ || threads_ == 1);
    if (!split) release_taken(mine.accepted, mine.taken);
    if (!private_state_) team_barrier();  // the shared state: every move is done first
    if (split) {                          // once no thread reads the shared marks
      release_taken(mine.uncontested, sel.taken);
      if (t == 0) release_taken(sel.accepted, sel.taken);
    }
    lap(st.advance_s);
  }

 private:
  const int threads_;
  const bool private_state_;
  std::vector<Selection> selections_;
  Selection team_selection_;  // the shared state's marks and contested candidates, where split
};

// How long a relay waiter spins before it yields (and then sleeps, parallel/relay.hpp): about a
// microsecond, whatever OMP_WAIT_POLICY says (psim makes it passive whenever threads outnumber
// cores, which is always so in the relay): only a closer and a taker per core wait there while
// the other threads sleep, so a microsecond's spin costs little. Not spinning cost about 1.2x.
inline constexpr int kRelaySpins = 256;

// A closer other than 0 that finds itself kLagRounds or more behind the last claimed round in
// kLagsToResign rounds stops closing (parallel/relay.hpp). Measured on the default scene at T = 3,
// 4, 8 on 2 cores (rounds 6 or more behind): none in 9 quiet runs, 650-850 of 1000 beside a busy
// neighbour.
inline constexpr std::uint64_t kLagRounds = ChunkRelay::kRounds / 4;
inline constexpr int kLagsToResign = 32;

// The relay (parallel/relay.hpp), for small scenes with more threads than cores: a round's chunks
// are the broad phase's pieces; a closer on each core runs everything else on its own copy of the
// state and of the broad phase, a second thread there takes chunks, and the rest sleep. Closer 0
// uses `broad` itself (its name() goes into the report) and writes its copy back for the time-unit
// callback and at the end.
template <BroadPhase Broad>
class RelayRun {
 public:
  // by_cpu: threads_by_cpu's lists; the first thread of each CPU closes, the second takes chunks.
  RelayRun(Broad& broad, const World& shared, const PipelineParams& params,
           const std::vector<std::vector<int>>& by_cpu)
      : broad_(broad),
        shared_(shared),
        params_(params),
        closers_(static_cast<int>(by_cpu[0].size())),
        threads_(params.threads),
        slot_of_(static_cast<std::size_t>(threads_), -1),
        report_(team_report(threads_)),
        scratch_(kRounds * static_cast<std::size_t>(threads_)),
        copies_of_broad_(static_cast<std::size_t>(closers_ - 1), broad),
        copies_(static_cast<std::size_t>(closers_)),
        rounds_(kRounds),
        substeps_(static_cast<std::uint64_t>(params.steps * params.slow_factor)),
        wall_chunks_(static_cast<std::uint32_t>((shared.n + kWallChunk - 1) / kWallChunk)),
        relay_(kRelaySpins, closers_) {
    for (int c = 0; c < closers_; ++c) slot_of_[by_cpu[0][c]] = c;
    if (by_cpu.size() > 1)
      for (std::size_t k = 0; k < by_cpu[1].size(); ++k)
        slot_of_[by_cpu[1][k]] = closers_ + static_cast<int>(k);
    broads_.push_back(&broad);
    for (Broad& b : copies_of_broad_) broads_.push_back(&b);
    for (StateCopy& copy : copies_) worlds_.push_back(copy.copy_of(shared));
    if (substeps_ == 0) relay_.finish();
  }

  RunReport run() {
#pragma omp parallel num_threads(threads_) if (substeps_ > 0)  // as in run_pipeline
    {
      const int t = omp_get_thread_num(), slot = slot_of_[t];
      if (slot < 0) {
        relay_.park();
      } else if (slot >= closers_) {
        take_chunks(slot);
      } else if (substeps_ > 0) {
        start_on_cpu(slot);  // one closer per core (parallel/relay.hpp)
        close(slot);
      }
      report_.cpus[t] = sched_getcpu();
    }
    finish_report(report_, total_, output_s_, substeps_done_, params_, scratch_, shared_,
                  broad_.name(), broad_.builds());
    return std::move(report_);
  }

 private:
  static constexpr std::uint64_t kRounds = ChunkRelay::kRounds;

  // Set by the opener of round r, in slot r % kRounds, for its chunks and its closing.
  struct Round {
    int source = 0;                 // the closer whose copy the chunks search
    std::uint32_t pair_chunks = 0;  // the broad phase's pieces (a round has at least one chunk)
    bool stop_seen = false;         // a stop request as read when the round opened
  };

  // What one closer keeps: its copy of the state and of the broad phase, its selection.
  struct Closer {
    int t;        // its index, 0 .. closers_ - 1 (not its thread's): its copy, its scratch slot
    bool master;  // closer 0: counts, profiles, writes its copy back
    const World& w;
    Broad& own;
    Selection sel;
    std::uint32_t chunks_so_far = 0;  // of every round up to the current one, modulo 2^32
    int lags = 0;                     // rounds closed kLagRounds or more behind
  };

  // Round r's candidates from thread t go to scratch_[(r % kRounds) * threads + t].
  ThreadScratch& scratch(std::uint64_t round, int t) {
    return scratch_[(round % kRounds) * threads_ + static_cast<std::size_t>(t)];
  }

  void search(const ChunkRelay::Ticket& ticket, int copy, int t) {
    if (ticket.chunk < rounds_[ticket.round % kRounds].pair_chunks)
      broads_[copy]->find_pairs_in(worlds_[copy], ticket.chunk, scratch(ticket.round, t));
  }

  // A thread that only takes chunks, until the run is finished.
  void take_chunks(int t) {
    while (relay_.wait_for_work()) {
      ChunkRelay::Ticket ticket;
      if (!relay_.take(ticket)) continue;
      search(ticket, rounds_[ticket.round % kRounds].source, t);
      relay_.finish_chunk();
    }
  }

  void lap(const Closer& c, double& stage) {
    if (params_.profile && c.master) watch_.lap(stage);
  }

  void close(int t) {
    const auto k = static_cast<std::size_t>(t);
    Closer c{t, t == 0, worlds_[k], *broads_[k], {}};
    c.sel.uses.assign(c.w.n, 0);
    c.sel.taken.assign(c.w.n, 0);
    std::uint64_t round = 1;
    prepare(c, round);
    while (close_round(c, round)) prepare(c, ++round);
    if (c.master) copies_[0].write_to(shared_);
  }

  // Builds this closer's structure for `round` and opens it if no other closer has.
  void prepare(Closer& c, std::uint64_t round) {
    StageTimes& st = report_.stages;
#pragma omp parallel num_threads(1)
    c.own.prepare(c.w);  // a team of one: no other thread is in a worksharing construct
    lap(c, st.broad_phase_s);
    const std::uint32_t pieces = c.own.chunks(c.w);
    const std::uint32_t chunks = std::max<std::uint32_t>(1, pieces);
    c.chunks_so_far += chunks;
    if (!relay_.claim(round)) return;
    relay_.wait_for_selections(round);
    for (int k = 0; k < threads_; ++k) scratch(round, k).clear_candidates();
    rounds_[round % kRounds] = {c.t, pieces, stop_requested(params_.stop)};
    // The opener finds the wall candidates itself: they read the whole state, which it has just
    // written (as chunks, other cores' reads cost more than the pass: 5 us a sub-step).
    ThreadScratch& mine = scratch(round, c.t);
    for (std::uint32_t w = 0; w < wall_chunks_; ++w) find_wall_candidates_in(c.w, w, mine);
    lap(c, st.narrow_phase_s);
    relay_.open(round, chunks);
  }

  // Closes `round`: its chunks, its collisions, its moves. False when this closer closes no more
  // (the run is over, or it resigned and now only takes chunks).
  bool close_round(Closer& c, std::uint64_t round) {
    StageTimes& st = report_.stages;
    relay_.wait_open(round);
    ChunkRelay::Ticket ticket;
    // A closer behind the open round closes its own first (with a busy neighbour on its core it
    // may fall behind); a chunk of a later round taken in a race searches the opener's copy.
    while (relay_.open_round() == round && relay_.take(ticket)) {
      search(ticket, ticket.round == round ? c.t : rounds_[ticket.round % kRounds].source, c.t);
      relay_.finish_chunk();
    }
    relay_.wait_done(c.chunks_so_far);
    lap(c, st.narrow_phase_s);  // up to the last chunk's candidates
    select_collisions(
        {&scratch(round, 0), static_cast<std::size_t>(threads_)}, c.sel, c.w, st,
        [&](double& stage) { lap(c, stage); }, c.master ? &report_.counters : nullptr);
    const bool last = rounds_[round % kRounds].stop_seen || round == substeps_;
    relay_.selected(c.t, round);
    if (!c.master && relay_.claimed() >= round + kLagRounds && ++c.lags == kLagsToResign) {
      relay_.resign(c.t);
      take_chunks(c.t);
      return false;
    }
    const std::uint64_t stopped = resolve_collisions(c.w, c.sel.accepted);
    if (c.master) report_.counters.wall_stops += stopped;  // every closer resolves them all
    lap(c, st.resolve_s);
    advance_free(c.w, c.sel.taken);
    release_taken(c.sel.accepted, c.sel.taken);
    lap(c, st.advance_s);
    if (c.master) count_substep(last);
    if (last) relay_.finish();
    return !last;
  }

  // Closer 0, after each sub-step: the count, and the time-unit callback on its copy.
  void count_substep(bool last) {
    ++substeps_done_;
    if (params_.on_time_unit && !last && substeps_done_ % params_.slow_factor == 0)
      observe(params_, substeps_done_ / params_.slow_factor, &copies_[0], shared_, watch_,
              unused_s_, output_s_);
  }

  Broad& broad_;
  const World& shared_;
  const PipelineParams& params_;
  const int closers_, threads_;
  // Per thread: its scratch slot, which for a closer is its index (below closers_), for a taker
  // one above; -1 for a thread that parks.
  std::vector<int> slot_of_;
  RunReport report_;
  std::vector<ThreadScratch> scratch_;
  std::vector<Broad> copies_of_broad_;
  std::vector<Broad*> broads_;
  std::vector<StateCopy> copies_;
  std::vector<World> worlds_;
  std::vector<Round> rounds_;
  Stopwatch total_, watch_;  // after the allocations, as the pipeline's
  double output_s_ = 0, unused_s_ = 0;
  const std::uint64_t substeps_;
  std::int64_t substeps_done_ = 0;  // closer 0's
  const std::uint32_t wall_chunks_;
  ChunkRelay relay_;
};

template <BroadPhase Broad>
RunReport run_relay(Broad& broad, const World& shared, const PipelineParams& params, int cpus) {
  return RelayRun<Broad>(broad, shared, params, threads_by_cpu(params.threads, cpus)).run();
}

// Test only (CMakeLists.txt, PARTICLE_PLANTED_SLOWDOWN): the pair search once more in every
// eighth sub-step, thrown away: a slowdown make regress must see. Nothing in other builds.
template <BroadPhase Broad>
void planted_slowdown([[maybe_unused]] Broad& broad, [[maybe_unused]] const World& w,
                      [[maybe_unused]] std::int64_t substep) {
#ifdef PARTICLE_PLANTED_SLOWDOWN
  if (substep % 8 == 0) {
    ThreadScratch wasted;
    find_pairs(broad, w, wasted);
  }
#endif
}

// team, no barrier at the end: the broad phase prepared (its time closed in broad_phase_s by
// lap), then this thread's share of the sub-step's wall and pair candidates in `found`.
template <BroadPhase Broad, class Lap>
void search_substep(Broad& broad, const World& w, ThreadScratch& found, std::int64_t substep,
                    Lap&& lap, double& broad_phase_s) {
  broad.prepare(w);
  lap(broad_phase_s);
  found.clear_candidates();
  find_walls(broad, w, found);
  find_pairs(broad, w, found);
  planted_slowdown(broad, w, substep);
}

template <BroadPhase Broad>
RunReport run_pipeline(Broad& broad, const World& shared, const PipelineParams& params) {
  const int threads = params.threads;
  const bool private_state = uses_private_state(shared.n);
  const int cpus = available_cpus();
  if (private_state && threads > cpus) return run_relay(broad, shared, params, cpus);
  RunReport report = team_report(threads);
  // Candidates of sub-step k go to scratch[(k % 2) * threads + t]: with one barrier per sub-step a
  // thread may write the next sub-step's candidates while another still selects from these.
  std::vector<ThreadScratch> scratch(2 * static_cast<std::size_t>(threads));
  SubstepCollisions collisions(threads, private_state, shared.n);
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
  std::atomic<int> arrived{0};
  Team team(threads);
  const int first_cpu = sched_getcpu();
  // S = 0 starts no team: its threads' start and idle spin would be all that such a run pays for T.
#pragma omp parallel num_threads(threads) if (params.steps > 0)
  {
    const int t = omp_get_thread_num();
    const TeamScope scope(team);
    spread_team(arrived, first_cpu);
    const bool master = t == 0;
    const auto lap = [&](double& stage) {
      if (profile && master) watch.lap(stage);
    };
    const World w = private_state ? copies[t].copy_of(shared) : shared;
    collisions.start(t, w.n);
    // The particles this thread moves: all of its private copy, or its share of the shared state.
    const std::size_t first = private_state ? 0 : w.n * t / threads;
    const std::size_t last = private_state ? w.n : w.n * (t + 1) / threads;
    int parity = 0;
    bool stopping = false;
    for (std::int64_t step = 1; step <= params.steps && !stopping; ++step) {
      for (int sub = 0; sub < params.slow_factor && !stopping; ++sub, parity ^= 1) {
        if (master) stop_seen[parity] = stop_requested(params.stop);
        ThreadScratch& found = scratch[static_cast<std::size_t>(parity * threads + t)];
        search_substep(broad, w, found, step * params.slow_factor + sub, lap, st.broad_phase_s);
        team_barrier();  // the private state's one barrier of a sub-step: all candidates are in
        stopping = stop_seen[parity];
        lap(st.narrow_phase_s);  // up to the last thread's candidates
        collisions.apply(t, {scratch.data() + parity * threads, static_cast<std::size_t>(threads)},
                         w, first, last, found, st, lap, master ? &report.counters : nullptr);
        if (master) ++substeps_done;
      }
      if (params.on_time_unit && step < params.steps && !stopping) {
        if (master)
          observe(params, step, private_state ? &copies[0] : nullptr, shared, watch, unused_s,
                  output_s);
        if (!private_state) team_barrier();  // the shared state must not move while printed
      }
    }
    if (private_state && master) copies[0].write_to(shared);  // every copy holds the same state
    report.cpus[t] = sched_getcpu();
  }
  finish_report(report, total, output_s, substeps_done, params, scratch, shared, broad.name(),
                broad.builds());
  return report;
}

}  // namespace particle::detail
