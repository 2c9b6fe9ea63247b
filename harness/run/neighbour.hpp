// A controlled busy neighbour: one process that spins on one CPU for as long as the object lives,
// so a sweep can show how the engines cope with a machine they do not have to themselves (the
// `neighbour` parameter, "busy" or "none"). It runs on the last CPU psweep may use, so a T=1 run
// pinned "close" (to the first) has a free core and T >= 2 shares one with the spinner.
#pragma once

#include <sys/types.h>

namespace psweep {

class BusyNeighbour {
 public:
  // Forks the spinner pinned to `cpu`; throws std::runtime_error if it cannot.
  explicit BusyNeighbour(int cpu);
  ~BusyNeighbour();  // kills and reaps it
  BusyNeighbour(const BusyNeighbour&) = delete;
  BusyNeighbour& operator=(const BusyNeighbour&) = delete;

  pid_t pid() const { return pid_; }

  // The last CPU of this process's affinity mask.
  static int last_cpu();

 private:
  pid_t pid_ = -1;
};

}  // namespace psweep
