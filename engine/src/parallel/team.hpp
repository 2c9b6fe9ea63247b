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
  // Spins as long as libgomp would before it yields and sleeps (GOMP_SPINCOUNT's 300,000, or
  // 1,000 once the team outnumbers the CPUs), or not at all under OMP_WAIT_POLICY=passive, which
  // psim sets when the cores are busy (wait_policy.hpp).
  explicit Team(int threads);

  // Every thread of the team: returns once all have called it, with everything each wrote before
  // visible to all.
  void wait();

  // Thread t of the team, at its `call`-th team_for: [first, last) becomes its share to take.
  void open_share(int t, std::uint32_t call, std::uint32_t first, std::uint32_t last);
  // A piece of thread `owner`'s share at its `call`-th team_for: the first one left when the owner
  // takes (from_front), else the last one; false when none is left, or the owner has not opened
  // that share yet (it then takes every piece itself).
  bool take(int owner, std::uint32_t call, bool from_front, std::uint32_t& piece);

  int threads() const { return static_cast<int>(threads_); }

 private:
  static constexpr int kYields = 16;
  // A share: the call's low 8 bits, its next piece and its end (28 bits each), in one word so
  // that a taker sees all three together. The threads of a team are never 256 calls apart: a
  // sub-step's team_for calls have a barrier after them.
  struct alignas(64) Share {
    std::atomic<std::uint64_t> word{0};
  };
  std::uint32_t threads_;
  int spins_ = 0;
  alignas(64) std::atomic<std::uint32_t> arrived_{0};
  alignas(64) std::atomic<std::uint32_t> generation_{0};
  std::unique_ptr<Share[]> shares_;
};

// The calling thread's team, the nesting level of that team, and how many team_for calls the
// thread has made in it.
struct InstalledTeam {
  Team* team = nullptr;
  int level = -1;
  std::uint32_t calls = 0;
};
inline thread_local InstalledTeam installed_team;

// Every thread of a team, inside its parallel region: team_barrier(), team_single() and
// team_for() use `team` until the scope ends.
class TeamScope {
 public:
  explicit TeamScope(Team& team) : saved_(installed_team) {
    installed_team = {&team, omp_get_level(), 0};
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
// go to the others. Every thread of the team must make the same calls in the same order.
template <class F>
void team_for(std::uint32_t pieces, F&& f) {
  Team* team = current_team();
  if (!team || pieces >= (std::uint32_t{1} << 28)) {
#pragma omp for schedule(dynamic, 1) nowait
    for (std::uint32_t piece = 0; piece < pieces; ++piece) f(piece);
    return;
  }
  const int threads = team->threads(), t = omp_get_thread_num();
  if (threads == 1) {
    for (std::uint32_t piece = 0; piece < pieces; ++piece) f(piece);
    return;
  }
  const std::uint32_t call = ++installed_team.calls;
  const auto share_edge = [&](int k) {
    return static_cast<std::uint32_t>(std::uint64_t{pieces} * static_cast<std::uint32_t>(k) /
                                      static_cast<std::uint32_t>(threads));
  };
  team->open_share(t, call, share_edge(t), share_edge(t + 1));
  std::uint32_t piece;
  while (team->take(t, call, true, piece)) f(piece);
  for (int k = 1; k < threads; ++k) {
    const int owner = (t + k) % threads;
    while (team->take(owner, call, false, piece)) f(piece);
  }
}

}  // namespace particle::detail
