// The launcher: how a run of psim whose engine uses P (mpi) starts its P ranks, declared once per
// config, as the words before psim's own (a program that lists "P" starts its ranks itself, with
// {P} in its command: config/program.hpp):
//
//   "launcher": ["srun", "-n", "{P}", "--cpus-per-task", "{T}"]
//
// Placeholders: {P}, which it must name (else every run would start as many ranks as the
// launcher's own default); {T}; and {rank_cores}, the cores each rank is bound to: T, at most
// this machine's online CPUs (OpenMPI refuses to bind a rank to more cores than there are).
// Without the key, default_launcher(): OpenMPI's mpirun, one rank per {rank_cores} cores in
// order (--map-by slot:PE), bound to them, more ranks than cores allowed (a sweep goes past the
// cores in P as it does in T), a rank that waits for a message yielding its core (OpenMPI spins
// otherwise, though --oversubscribe: N = 4000 on 2 cores, P = 2 x T = 2 took 7.34 s against
// 0.34 s yielding, P = 4 x T = 1 8.1 s against 0.34 s; P = 2 x T = 1 0.29-0.33 s either way),
// and --allow-run-as-root as root, which OpenMPI refuses otherwise.
#pragma once

#include <string>
#include <vector>

#include "config/config.hpp"

namespace psweep {

// The `launcher` key, checked: a ConfigError at its path for anything but a non-empty list of
// strings whose placeholders are {P}, {T} and {rank_cores}, {P} among them.
std::vector<std::string> parse_launcher(const Json& launcher, const std::string& path);

// mpirun -np {P} with ranks bound to their cores (above); `root`: psweep runs as root.
std::vector<std::string> default_launcher(bool root);

// The launcher's words for one run, placeholders filled and the first found on PATH; none for a
// run without P (an engine that does not use it). `cpus`: this machine's online CPUs.
std::vector<std::string> launcher_arguments(const std::vector<std::string>& launcher,
                                            const Params& params, int cpus);

}  // namespace psweep
