// Tier: how a confined run is made on this machine (docs/programs.md, "Confinement"). Two
// implementations of one interface, chosen once per sweep, the strongest the machine allows:
//   - `bwrap` (run/confine.hpp): namespaces of its own for everything (PID, network, mounts),
//     where the kernel lets an unprivileged user make them;
//   - `landlock+seccomp` (run/contain.hpp): no new namespace (Docker's default seccomp profile,
//     Gradescope's and CI's containers refuse them), the kernel's Landlock and a seccomp filter
//     instead, the run as its own user where psweep is root.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "run/counters.hpp"
#include "run/runner.hpp"

namespace psweep {

class Tier {
 public:
  virtual ~Tier() = default;
  // meta.json's confinement.tool, and the word psweep prints.
  virtual std::string name() const = 0;
  // `argv` (argv[0] the program, the words naming files staged with it) run confined with `env`
  // (its OMP_* and the config's `env`) under the program's limits and the sweep's timeout, its
  // output bounded by `file_bytes`; `io` says its stdin, stdout, CPUs and user.
  virtual ChildResult run(const Program& program, const std::vector<std::string>& argv,
                          const std::vector<std::string>& env, double timeout_s, int threads,
                          std::uint64_t file_bytes, ChildIo io,
                          const CounterAvailability* counters) = 0;
  // The least time, of 5, that a confined `true` takes: part of every run's process_s.
  virtual double start_s() = 0;
};

// The strongest tier this machine allows (`hide`: the repository, results and psim folders,
// which no run may see); nullptr and `why` (each tier's reason) when none works.
std::unique_ptr<Tier> strongest_tier(const std::vector<std::string>& hide, std::string& why);

}  // namespace psweep
