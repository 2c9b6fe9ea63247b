#pragma once
// The barrier, the single and the work split of the engines' OpenMP teams, in place of
// `#pragma omp barrier`, `#pragma omp single` and `#pragma omp for schedule(dynamic, 1) nowait`.
// libgomp's barrier wakes its futex every time, sleepers or not, and on this project's VMs that
// system call is most of its cost (two threads on the 2-core AMD EPYC VM: 1.4 to 1.6 us a barrier
// against 0.23 us for Team's; a team of one paid about 1 us too). The default scene's sub-step has
// one barrier, the slow crowd's about seven. libgomp's dynamic loop hands every piece out from one
// shared counter, to whichever thread asks; team_for gives each thread its own contiguous share
// first, the pieces next to the data it built (the million scene's cells at T = 2: a tenth less
// loop, docs/performance.md, History), and lets the others take what a late thread leaves.
//
// A team that runs broad phases installs a Team for its threads (TeamScope, inside its parallel
// region); in any other team, a nested one included, these are OpenMP's.
#include <omp.h>

#include <atomic>
#include <cstdint>
#include <memory>

namespace particle::detail {

class Team {
 public:
  // Spins as long as libgomp's default would before it yields and sleeps (GOMP_SPINCOUNT's
  // 300,000, or 1,000 once the team outnumbers the CPUs), whatever psim has libgomp itself spin
  // (apps/psim.cpp), or not at all under OMP_WAIT_POLICY=passive, which psim sets when the cores
  // are busy (wait_policy.hpp).
  explicit Team(int threads);

  // Every thread of the team: returns once all have called it, with everything each wrote before
  // visible to all.
  void wait();

  // Thread t, entering a team_for of `pieces`: the call's number (thread t's count of its
  // team_for calls on this team, over every parallel region it served), with every thread's share
  // of the pieces open to take, whichever thread came first. A share it replaces, of an earlier
  // call, has been taken whole: the thread that opened this call left that one only when it had.
  // A share of a later call (a thread already there) stays: this call's pieces are all taken.
  std::uint32_t open_shares(int t, std::uint32_t pieces);
  // A piece of thread `owner`'s share at the `call`-th team_for: the first one left when the
  // owner takes (from_front), else the last one; false when none is left.
  bool take(int owner, std::uint32_t call, bool from_front, std::uint32_t& piece);

  int threads() const { return static_cast<int>(threads_); }

 private:
  static constexpr int kYields = 16;
  // A share: the call's low 8 bits, its next piece and its end (28 bits each), in one word so
  // that a taker sees all three together. The threads of a team are never 128 calls apart (a
  // sub-step's calls have a barrier after them), so 8 bits tell calls apart.
  struct alignas(64) Share {
    std::atomic<std::uint64_t> word{0};
    std::uint32_t calls = 0;  // its owner's team_for calls: only the owner reads or writes it
  };
  Share& share(int owner) { return shares_[static_cast<std::size_t>(owner)]; }
  std::uint32_t threads_;
  int spins_ = 0;
  alignas(64) std::atomic<std::uint32_t> arrived_{0};
  alignas(64) std::atomic<std::uint32_t> generation_{0};
  std::unique_ptr<Share[]> shares_;
};

// The calling thread's team and the nesting level of that team.
struct InstalledTeam {
  Team* team = nullptr;
  int level = -1;
};
inline thread_local InstalledTeam installed_team;

// Every thread of a team, inside its parallel region: team_barrier(), team_single() and
// team_for() use `team` until the scope ends.
class TeamScope {
 public:
  explicit TeamScope(Team& team) : saved_(installed_team) {
    installed_team = {&team, omp_get_level()};
  }
  ~TeamScope() { installed_team = saved_; }
  TeamScope(const TeamScope&) = delete;
  TeamScope& operator=(const TeamScope&) = delete;

 private:
  InstalledTeam saved_;
};

// The installed team where the calling thread's innermost team is it, else null.
inline Team* current_team() {
  const InstalledTeam& installed = installed_team;
  return installed.team && installed.level == omp_get_level() ? installed.team : nullptr;
}

// team: `#pragma omp barrier`.
void team_barrier();

// team: `#pragma omp single`, on thread 0.
template <class F>
void team_single(F&& f) {
  if (omp_get_thread_num() == 0) f();
  team_barrier();
}

// team, no barrier: f(piece) once for every piece in [0, pieces) over the team, as `#pragma omp
// for schedule(dynamic, 1) nowait`. Each thread takes its own contiguous share in order, then
// takes from the back of the others' shares what they have not begun, so a late thread's pieces
// go to the others, even before it arrives. Every thread of the team must make the same calls in
// the same order.
template <class F>
void team_for(std::uint32_t pieces, F&& f) {
  if (omp_get_num_threads() == 1) {
    for (std::uint32_t piece = 0; piece < pieces; ++piece) f(piece);
    return;
  }
  Team* team = current_team();
  if (!team || pieces >= (std::uint32_t{1} << 28)) {
#pragma omp for schedule(dynamic, 1) nowait
    for (std::uint32_t piece = 0; piece < pieces; ++piece) f(piece);
    return;
  }
  const int threads = team->threads(), t = omp_get_thread_num();
  const std::uint32_t call = team->open_shares(t, pieces);
  std::uint32_t piece;
  while (team->take(t, call, true, piece)) f(piece);
  for (int k = 1; k < threads; ++k) {
    const int owner = (t + k) % threads;
    while (team->take(owner, call, false, piece)) f(piece);
  }
}

}  // namespace particle::detail
