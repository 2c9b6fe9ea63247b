#include "particle/wait_policy.hpp"

#include <sched.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

namespace particle {

WaitPolicy choose_wait_policy(int threads, int cpus, int others_running) {
  if (threads > cpus) return {"passive", "oversubscribed"};
  if (others_running + threads > cpus) return {"passive", "loaded"};
  return {"default", "quiet"};
}

int available_cpus() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return 1;
  return std::max(1, CPU_COUNT(&set));
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
  }
  return std::max(0, fewest - 1);
}

}  // namespace particle
