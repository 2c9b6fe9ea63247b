#pragma once
// How idle OpenMP threads wait at a barrier, chosen for the machine a run finds.
//
// libgomp's default spins a while before sleeping: the fastest hand-over when every thread has a
// core of its own, and ruinous when a waiting thread spins on the core that the thread it waits
// for needs (more threads than cores, or other busy processes): a run of 1000 sub-steps with one
// barrier each then takes seconds instead of a tenth of one. A passive policy sleeps at once. The
// OpenMP runtime reads OMP_WAIT_POLICY only when it starts, so psim decides before that and
// re-executes itself with the variable set (see apps/psim.cpp); a policy the user set wins.
#include <atomic>
#include <string>
#include <vector>

namespace particle {

struct WaitPolicy {
  std::string policy;  // "passive", "default" (the runtime's spin-then-sleep), or the user's value
  std::string reason;  // why, for the metrics: "OMP_WAIT_POLICY", "oversubscribed", "loaded",
                       // "quiet", "one thread" (psim at T = 1: no thread ever waits)
};

// Pure: passive when the threads outnumber the CPUs the process may use, or when the other
// runnable tasks and the threads together do; otherwise the runtime's default.
WaitPolicy choose_wait_policy(int threads, int cpus, int others_running);

// The CPUs this process may run on: its OpenMP places when threads are bound (the initial
// thread is then already pinned to one place), else its affinity mask.
int available_cpus();

// Gives the calling thread the whole process's CPUs back before psim re-executes itself, so the
// new runtime lays out its places over all of them instead of the one place it was pinned to.
void unpin_initial_thread();

// Moves the calling thread to the k-th of the process's CPUs (k modulo their count) and lets it
// run on all of them again: the kernel keeps a thread where it is while the load stays even, so
// threads started this way start out spread over the cores. Nothing when OpenMP binds threads.
void start_on_cpu(int k);

// team: spreads the team over the process's CPUs and waits, yielding, until `arrived` counts the
// whole team. Thread 0 stays where it is (on first_cpu, which the master read before the team
// started: it keeps its cache), thread t moves t CPUs past it (start_on_cpu; nothing when
// OpenMP binds threads). libgomp starts a new thread on its creator's CPU, where the creator,
// spinning at the team's first barrier, kept it from running: 8 to 15 ms in 7 of 10 runs of the
// default scene at T = 2 on 2 cores (docs/performance.md). The yield hands it the CPU.
void spread_team(std::atomic<int>& arrived, int first_cpu);

// The threads of a team of `threads` by the CPU they run on: element k lists the k-th thread of
// every CPU, in thread order, so element 0 gives each CPU one thread, element 1 a second, and so
// on. Where OpenMP binds threads, a CPU is a place (OMP_PROC_BIND=close binds threads 0-3 of
// T = 8 to the first of 2 places); else thread t counts as CPU t mod `cpus` (start_on_cpu moves
// it there). Thread 0 is always first.
std::vector<std::vector<int>> threads_by_cpu(int threads, int cpus);

// Runnable tasks on the machine besides the caller, from /proc/stat (the fewest of a few samples
// a millisecond apart, so a short-lived process does not count); 0 where it cannot be read.
int other_running_tasks();

}  // namespace particle
