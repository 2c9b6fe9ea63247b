#pragma once
// The relay: how threads share a sub-step of a small scene (below kPrivateStateBelow particles)
// when they outnumber the process's cores. Every thread keeping a private copy of the state (one
// barrier per sub-step, private_state.hpp) is fastest while each has a core; with more threads
// than cores every extra thread repeats the serial stages, and the barrier waits each sub-step
// (about 70 us on the default scene) for whichever thread the kernel has descheduled.
//
// Here a sub-step is a round of chunks (the broad phase's pieces of the pair search) that any
// thread takes with one atomic increment. When the last chunk is done, thread 0 (the closer; always
// the same thread, so the state and the broad phase's structure stay in its cache) selects and
// applies the collisions, builds the next sub-step's broad-phase structure and opens the next
// round. The others wait for that round: a thread that is descheduled holds up nobody unless it
// holds a chunk, a late thread simply finds the chunks taken, and extra threads add no work. The
// candidate set does not depend on who took which chunk, and the selection orders it totally, so
// the state is bit-identical for every thread count.
//
// Waiting: a short spin, then sched_yield() (so a waiter that shares a core with a working thread
// gives the core back at once); under OMP_WAIT_POLICY=passive (psim sets it when threads
// outnumber the free cores, wait_policy.hpp) a waiter yields from the start.
#include <sched.h>

#include <atomic>
#include <cstdint>

namespace particle::detail {

class ChunkRelay {
 public:
  static constexpr std::uint64_t kFinished = ~std::uint64_t{0};

  // spins: pause iterations before a waiter starts yielding.
  explicit ChunkRelay(int spins) : spins_(spins) {}

  // The closer (or any thread before the others start): opens round `round` (not
  // kFinished) of `chunks` chunks, at least one. Everything written before is visible to the
  // takers.
  void open(std::uint64_t round, std::uint32_t chunks) {
    done_.store(0, std::memory_order_relaxed);
    work_.store(std::uint64_t{chunks} << 32, std::memory_order_release);
    round_.store(round, std::memory_order_release);
  }
  // One thread: no more rounds; every waiter leaves.
  void finish() {
    work_.store(0, std::memory_order_release);
    round_.store(kFinished, std::memory_order_release);
  }

  std::uint64_t round() const { return round_.load(std::memory_order_acquire); }

  struct Ticket {
    std::uint32_t chunk = 0, chunks = 0;
  };
  // Takes the next chunk of the open round; false when all are taken. Increments past the end
  // are harmless: at most one per thread and round, far from the 32 bits above.
  bool take(Ticket& ticket) {
    const std::uint64_t word = work_.fetch_add(1, std::memory_order_acq_rel);
    ticket.chunk = static_cast<std::uint32_t>(word);
    ticket.chunks = static_cast<std::uint32_t>(word >> 32);
    return ticket.chunk < ticket.chunks;
  }
  // After a chunk is done (its results become visible to wait_done()).
  void finish_chunk() { done_.fetch_add(1, std::memory_order_release); }

  // The closer: returns once every chunk of the open round (of `chunks`) is finished, with their
  // results visible.
  void wait_done(std::uint32_t chunks) const {
    for (int spin = 0; done_.load(std::memory_order_acquire) != chunks; ++spin)
      pause_or_yield(spin);
  }

  // Returns once the open round is no longer `round`.
  void wait_past(std::uint64_t round) const {
    for (int spin = 0; round_.load(std::memory_order_acquire) == round; ++spin)
      pause_or_yield(spin);
  }

 private:
  void pause_or_yield(int spin) const {
    if (spin < spins_) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
    } else {
      sched_yield();
    }
  }

  int spins_;
  alignas(64) std::atomic<std::uint64_t> work_{0};  // chunks of the round << 32 | next chunk
  alignas(64) std::atomic<std::uint32_t> done_{0};  // chunks of the round finished
  alignas(64) std::atomic<std::uint64_t> round_{0};
};

}  // namespace particle::detail
