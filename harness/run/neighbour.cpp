#include "run/neighbour.hpp"

#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "run/runner.hpp"

namespace psweep {

BusyNeighbour::BusyNeighbour(int cpu) {
  const pid_t self = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error(std::string("neighbour: fork: ") + std::strerror(errno));
  if (pid_ == 0) {  // the child: async-signal-safe calls only, then spin until killed
    die_with_parent(self);
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    sched_setaffinity(0, sizeof set, &set);
    volatile unsigned long spins = 0;
    for (;;) spins = spins + 1;
  }
}

BusyNeighbour::~BusyNeighbour() {
  kill(pid_, SIGKILL);
  while (waitpid(pid_, nullptr, 0) < 0 && errno == EINTR) {
  }
}

int BusyNeighbour::last_cpu() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return 0;
  int last = 0;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) last = c;
  return last;
}

}  // namespace psweep
