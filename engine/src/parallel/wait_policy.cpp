#include "particle/wait_policy.hpp"

#include <omp.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>
#include <vector>

namespace particle {

WaitPolicy choose_wait_policy(int threads, int cpus, int others_running) {
  if (threads > cpus) return {"passive", "oversubscribed"};
  if (others_running + threads > cpus) return {"passive", "loaded"};
  return {"default", "quiet"};
}

namespace {

// With OMP_PROC_BIND set, libgomp binds the initial thread to the first place when it loads, so
// the thread's own mask then shows one place; the places list keeps what the process was given.
cpu_set_t process_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  const int places = omp_get_num_places();
  for (int place = 0; place < places; ++place) {
    std::vector<int> ids(omp_get_place_num_procs(place));
    omp_get_place_proc_ids(place, ids.data());
    for (int id : ids) CPU_SET(id, &set);
  }
  if (CPU_COUNT(&set) == 0 && sched_getaffinity(0, sizeof set, &set) != 0) CPU_SET(0, &set);
  return set;
}

}  // namespace

int available_cpus() {
  const cpu_set_t set = process_cpus();
  return std::max(1, CPU_COUNT(&set));
}

void unpin_initial_thread() {
  const cpu_set_t set = process_cpus();
  sched_setaffinity(0, sizeof set, &set);
}

void start_on_cpu(int k) {
  if (omp_get_proc_bind() != omp_proc_bind_false) return;  // the user's binding stands
  const cpu_set_t all = process_cpus();
  const int wanted = k % CPU_COUNT(&all);
  for (int id = 0, seen = 0; id < CPU_SETSIZE; ++id) {
    if (!CPU_ISSET(id, &all) || seen++ != wanted) continue;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(id, &one);
    sched_setaffinity(0, sizeof one, &one);  // moves the thread there before it returns
    break;
  }
  sched_setaffinity(0, sizeof all, &all);
}

void spread_team(std::atomic<int>& arrived, int first_cpu) {
  if (const int t = omp_get_thread_num(); t > 0) {
    // first_cpu's rank among the process's CPUs (0 for one not among them).
    const cpu_set_t all = process_cpus();
    int rank = 0;
    if (first_cpu >= 0 && first_cpu < CPU_SETSIZE && CPU_ISSET(first_cpu, &all))
      for (int id = 0; id < first_cpu; ++id) rank += CPU_ISSET(id, &all) ? 1 : 0;
    start_on_cpu(rank + t);
  }
  arrived.fetch_add(1);
  while (arrived.load() < omp_get_num_threads()) sched_yield();
}

std::vector<std::vector<int>> threads_by_cpu(int threads, int cpus) {
  std::vector<int> cpu(static_cast<std::size_t>(threads));
  if (omp_get_proc_bind() == omp_proc_bind_false) {
    for (int t = 0; t < threads; ++t) cpu[t] = t % std::max(1, cpus);
  } else {
#pragma omp parallel num_threads(threads)
    cpu[static_cast<std::size_t>(omp_get_thread_num())] = omp_get_place_num();
  }
  std::vector<std::vector<int>> by_cpu;
  std::map<int, std::size_t> seen;  // cpu -> its threads so far
  for (int t = 0; t < threads; ++t) {
    const std::size_t k = seen[cpu[t]]++;
    if (by_cpu.size() <= k) by_cpu.emplace_back();
    by_cpu[k].push_back(t);
  }
  return by_cpu;
}

namespace {

// procs_running of /proc/stat: runnable tasks now, the reader included; -1 if unreadable.
int procs_running() {
  std::ifstream stat("/proc/stat");
  std::string line;
  while (std::getline(stat, line))
    if (line.rfind("procs_running ", 0) == 0) return std::stoi(line.substr(14));
  return -1;
}

}  // namespace

int other_running_tasks() {
  int fewest = -1;
  for (int sample = 0; sample < 3; ++sample) {
    if (sample) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const int now = procs_running();
    if (now < 0) return 0;
    fewest = fewest < 0 ? now : std::min(fewest, now);
    // Only the reader runs: no later sample can show fewer, and a quiet machine, where every
    // timed run starts, would otherwise wait 2 ms for nothing (a twentieth of auto's T = 2 run
    // of the default scene).
    if (fewest <= 1) break;
  }
  return std::max(0, fewest - 1);
}

}  // namespace particle
