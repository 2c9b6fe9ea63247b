#include "parallel/team.hpp"

#include <strings.h>

#include <cstdlib>

#include "parallel/wait.hpp"
#include "particle/wait_policy.hpp"

namespace particle::detail {

namespace {

constexpr std::uint64_t kPieceMask = (std::uint64_t{1} << 28) - 1;

std::uint64_t share_word(std::uint32_t call, std::uint64_t next, std::uint64_t end) {
  return std::uint64_t{call & 0xffu} << 56 | end << 28 | next;
}

}  // namespace

Team::Team(int threads)
    : threads_(static_cast<std::uint32_t>(threads)),
      shares_(new Share[static_cast<std::size_t>(threads)]) {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (policy && strcasecmp(policy, "passive") == 0)
    spins_ = 0;
  else
    spins_ = threads > available_cpus() ? 1000 : 300000;
}

// The generation is read before arriving: it cannot move until this thread has.
void Team::wait() {
  const std::uint32_t generation = generation_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == threads_) {
    arrived_.store(0, std::memory_order_relaxed);  // before the release below
    generation_.store(generation + 1, std::memory_order_release);
    generation_.notify_all();
    return;
  }
  wait_until(
      generation_, [&](std::uint32_t seen) { return seen != generation; }, spins_, kYields);
}

// Relaxed: what the pieces read was written before the barrier that precedes every team_for,
// and what they write is read after the one that follows it.
std::uint32_t Team::open_shares(int t, std::uint32_t pieces) {
  const std::uint32_t call = ++share(t).calls;
  for (std::uint32_t k = 0; k < threads_; ++k) {
    std::atomic<std::uint64_t>& word = share(static_cast<int>(k)).word;
    const std::uint64_t first = std::uint64_t{pieces} * k / threads_,
                        last = std::uint64_t{pieces} * (k + 1) / threads_;
    std::uint64_t seen = word.load(std::memory_order_relaxed);
    // Only a share of an earlier call is replaced (its call before this one, modulo 256).
    while (static_cast<std::int8_t>(static_cast<std::uint8_t>((seen >> 56) - call)) < 0 &&
           !word.compare_exchange_weak(seen, share_word(call, first, last),
                                       std::memory_order_relaxed)) {
    }
  }
  return call;
}

bool Team::take(int owner, std::uint32_t call, bool from_front, std::uint32_t& piece) {
  std::atomic<std::uint64_t>& word = share(owner).word;
  std::uint64_t seen = word.load(std::memory_order_relaxed);
  for (;;) {
    const std::uint64_t next = seen & kPieceMask, end = seen >> 28 & kPieceMask;
    if (seen >> 56 != (call & 0xffu) || next >= end) return false;
    const std::uint64_t taken =
        from_front ? share_word(call, next + 1, end) : share_word(call, next, end - 1);
    if (word.compare_exchange_weak(seen, taken, std::memory_order_relaxed)) {
      piece = static_cast<std::uint32_t>(from_front ? next : end - 1);
      return true;
    }
  }
}

void team_barrier() {
  if (omp_get_num_threads() == 1) return;
  if (Team* team = current_team())
    team->wait();
  else {
#pragma omp barrier
  }
}

}  // namespace particle::detail
