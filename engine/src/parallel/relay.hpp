#pragma once
// The relay: how threads share a sub-step of a small scene (below kPrivateStateBelow particles)
// when they outnumber the process's cores. Every thread keeping a private copy of the state (one
// barrier per sub-step, parallel/private_state.hpp) is fastest while each has a core; with more
// threads than cores every extra thread repeats the serial stages, and the barrier waits each
// sub-step (about 70 us on the default scene) for whichever thread the kernel has descheduled.
//
// Here a sub-step is a round of chunks (the broad phase's pieces of the pair search) that any
// thread takes with one atomic increment. One thread per core (the closers, threads 0 .. C-1)
// keeps a private copy of the state and of the broad phase's structure, as every thread does at
// T <= cores: when the last chunk of a round is done, each closer selects and applies the
// collisions to its own copy and builds its next structure; the first one ready opens the next
// round, whose chunks every thread then searches in the opener's structure (a closer in its own,
// once it is ready). So the serial stages run on every core at once and each closer's data stays
// in its own cache (with a single closer they took twice their T=1 time, and the other core sat
// idle meanwhile). One more thread per core only takes chunks: it runs while a closer of its core
// waits. The others park until the run ends (park()): they could only take chunks from the
// others, at the price of a wake-up each round (all of them taking chunks, T = 8 on 2 cores made
// 21 context switches a sub-step and took 1.5x T = 2's time). Where OpenMP binds threads, the
// closers are the first thread on each place, not threads 0 .. C-1, which close binding puts on
// one core (threads_by_cpu), and the takers the second thread on each. A closer that resigns
// (below) takes chunks too. The candidate set does not depend on who took which chunk, and the
// selection orders it totally, so every copy stays bit-identical to the single-thread state for
// every thread count.
//
// Round r's candidates go to buffers of slot r % kRounds, so closers need not keep in step: a
// closer may select round r while later rounds are searched, and round r + kRounds (which reuses
// the slot) opens only once every closer has selected round r. A closer that is behind closes its
// own rounds before it takes chunks again. A closer sharing its core with a busy process falls
// behind by several rounds, round after round; it then resigns (step/pipeline.hpp: after 32 rounds
// 8 or more behind, which quiet runs never showed) and only takes chunks from then on, so the
// others no longer wait for it. Closer 0 never resigns: its copy is the run's state.
//
// Closer c starts on the process's c-th core (start_on_cpu): the kernel rarely moves a thread
// while the load is even, and two closers sharing a core while the other one ran only a taker made
// a third of the runs at T = 3 about 1.4x slower.
//
// Waiting: parallel/wait.hpp's spin, yields and sleep.
#include <atomic>
#include <cstdint>
#include <memory>

#include "parallel/wait.hpp"

namespace particle::detail {

class ChunkRelay {
 public:
  // Rounds whose candidates are kept: a closer may fall this many rounds behind the opener (2
  // made the others wait for a closer beside a busy neighbour, for up to a time slice each time).
  static constexpr std::uint32_t kRounds = 32;

  // spins: pause iterations before a waiter starts yielding; closers: how many threads select.
  ChunkRelay(int spins, int closers)
      : spins_(spins), closers_(closers), selected_(new Slot[static_cast<std::size_t>(closers)]) {}

  // A closer that has prepared round `round` (1, 2, ...): true for the first of them to ask,
  // which then opens it.
  bool claim(std::uint64_t round) {
    std::uint64_t previous = round - 1;
    return claimed_.compare_exchange_strong(previous, round, std::memory_order_acq_rel);
  }

  // The claimant of round `round`: returns once every closer (but those that resigned) has
  // selected round - kRounds, whose candidate buffers the round reuses.
  void wait_for_selections(std::uint64_t round) const {
    const auto r = static_cast<std::uint32_t>(round);
    for (int c = 0; c < closers_; ++c)
      wait_on(selected_[c].value, [&](std::uint32_t selected) {
        return static_cast<std::int32_t>(selected + kRounds - r) >= 0 ||
               selected_[c].resigned.load(std::memory_order_relaxed);
      });
  }

  // The last round claimed.
  std::uint64_t claimed() const { return claimed_.load(std::memory_order_relaxed); }

  // Closer c, after selected(): it closes no more rounds (from now on it only takes chunks), so
  // no claimant waits for its selections.
  void resign(int c) {
    selected_[c].resigned.store(true, std::memory_order_relaxed);
    selected_[c].value.fetch_add(1, std::memory_order_release);  // wakes a claimant waiting on c
    selected_[c].value.notify_all();
  }

  // The claimant: opens round `round` of `chunks` chunks (at least one). Everything written
  // before is visible to whoever takes one of its chunks.
  void open(std::uint64_t round, std::uint32_t chunks) {
    round_.store(round, std::memory_order_relaxed);
    work_.store(std::uint64_t{chunks} << 32, std::memory_order_release);
    wake_takers();
  }

  // Any thread: no more rounds; every waiting or parked thread leaves.
  void finish() {
    finished_.store(true, std::memory_order_release);
    finished_.notify_all();
    wake_takers();
  }

  // A thread beyond a closer and a taker per core: it would add no work, only wake-ups. It sleeps
  // until the run is finished.
  void park() const {
    while (!finished_.load(std::memory_order_acquire))
      finished_.wait(false, std::memory_order_acquire);
  }

  // The round opened last.
  std::uint64_t open_round() const { return round_.load(std::memory_order_relaxed); }

  struct Ticket {
    std::uint32_t chunk = 0;
    std::uint64_t round = 0;
  };
  // Takes the next chunk of the open round; false when all are taken. The round cannot close
  // while one of its chunks is held, so the round read after a successful take is the chunk's.
  // Increments past the end are harmless: a few per thread and round, far from the 32 bits above.
  bool take(Ticket& ticket) {
    const std::uint64_t word = work_.fetch_add(1, std::memory_order_acq_rel);
    ticket.chunk = static_cast<std::uint32_t>(word);
    if (ticket.chunk >= static_cast<std::uint32_t>(word >> 32)) return false;
    ticket.round = round_.load(std::memory_order_relaxed);
    return true;
  }
  // After a chunk is done (its results become visible to wait_done()).
  void finish_chunk() {
    done_.fetch_add(1, std::memory_order_release);
    done_.notify_all();  // a load and nothing more while nobody sleeps
  }

  // A thread that only takes chunks: returns true once a chunk may be there to take, false
  // once the run is finished.
  bool wait_for_work() const {
    bool more = true;
    wait_on(
        opened_,
        [&](std::uint32_t) {
          const std::uint64_t word = work_.load(std::memory_order_acquire);
          if (static_cast<std::uint32_t>(word) < static_cast<std::uint32_t>(word >> 32))
            return true;
          more = !finished_.load(std::memory_order_acquire);
          return !more;
        },
        kTakerYields);
    return more;
  }

  // A closer that has prepared round `round` but did not open it: returns once it is open (the
  // opener finds the wall candidates first), so that it takes its share of the chunks.
  void wait_open(std::uint64_t round) const {
    const auto r = static_cast<std::uint32_t>(round);
    wait_on(opened_,
            [&](std::uint32_t opened) { return static_cast<std::int32_t>(opened - r) >= 0; });
  }

  // A closer: returns once `total` chunks (of all rounds so far, modulo 2^32) are finished, with
  // their results visible.
  void wait_done(std::uint32_t total) const {
    wait_on(done_,
            [&](std::uint32_t done) { return static_cast<std::int32_t>(done - total) >= 0; });
  }

  // Closer c has read round `round`'s candidates (and its stop flag).
  void selected(int c, std::uint64_t round) {
    selected_[c].value.store(static_cast<std::uint32_t>(round), std::memory_order_release);
    selected_[c].value.notify_all();
  }

 private:
  template <class Ready>
  void wait_on(const std::atomic<std::uint32_t>& word, Ready ready, int yields = kYields) const {
    wait_until(word, ready, spins_, yields);
  }
  void wake_takers() {
    opened_.fetch_add(1, std::memory_order_release);
    opened_.notify_all();
  }

  struct alignas(64) Slot {
    std::atomic<std::uint32_t> value{0};
    std::atomic<bool> resigned{false};
  };

  static constexpr int kYields = 16;  // 64 measured alike, 0 slower (a sleep too soon)
  // A taker waits about a round before it sleeps (the closers' serial stages take ~23 us on the
  // default scene): at T=8 3% faster than 16 in three batches, the same at T=3 and 4.
  static constexpr int kTakerYields = 64;
  int spins_, closers_;
  std::unique_ptr<Slot[]> selected_;  // the last round each closer selected, modulo 2^32
  alignas(64) std::atomic<std::uint64_t> work_{0};  // chunks of the round << 32 | next chunk
  alignas(64) std::atomic<std::uint32_t> done_{0};  // chunks finished, all rounds, modulo 2^32
  alignas(64) std::atomic<std::uint64_t> round_{0};
  alignas(64) std::atomic<std::uint64_t> claimed_{0};
  alignas(64) std::atomic<bool> finished_{false};
  // Rounds opened (modulo 2^32), plus one at finish(): what takers and closers sleep on.
  alignas(64) std::atomic<std::uint32_t> opened_{0};
};

}  // namespace particle::detail
