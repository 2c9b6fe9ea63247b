// Shard: the cost model of a run and a deterministic, cost-balanced split of a sweep's
// configurations over N machines (`psweep CONFIG --shard I/N`, one Slurm array task each).
//
// Cost model (seconds of one run, an estimate for balancing and for "how long would this take"):
//   process_s [+ launch_s + rank_step_s * S * K]
//     + (cost_ns + neighbour_ns * n) * 1e-9 * N^growth * S * K / min(T P, cpus)
// The engine figures come from psim's declaration (`psim --describe`): "growth" (N^2: every pair
// tested; N: cells, sorts, events), "cost_ns", one sub-step's time per particle (per pair for
// N^2) on one thread, and for N growth "neighbour_ns", what each of the n particles expected
// within a sub-step's reach adds to it (reach_neighbours: a fast scene makes the broad phase test
// hundreds of candidates per particle, a slow crowd none), measured per engine; so the model names
// no engine. An engine the declaration does not know (a program, a dry run without psim) grows as
// N at the default particle_step_s; one declared without cost_ns (an older psim) takes the default
// of its growth.
// K, T and P count as 1 where the engine ignores them; a run of P ranks (the bracket) adds its
// launcher's start and each sub-step's messages, and its P ranks share the work as threads do. Threads beyond `cpus` take turns instead of
// speeding a run up (the threads baseline: T = 3..8 as slow as T = 2 on 2 CPUs), so the size
// report sets the machine's CPUs; shards leave it 0 (as many as T), since each Slurm task gets
// --cpus-per-task of the largest T and the split must not depend on where it is computed.
// Within T <= cpus the speed-up counts as ideal (measured: 1.7-1.85 at T = 2, N = 2000).
//
// Partition: longest-processing-time first. Configurations sorted by cost, largest first (ties by
// expansion index), each given to the shard with the least cost so far (ties: the lowest shard).
// It depends only on the costs, so every array task computes the same split without talking to
// the others. A configuration is one unit: all its repetitions and warm-ups run in one shard, so
// its minimum is taken on one machine. Balance: the largest shard is at most the mean plus the
// largest configuration, and at most 4/3 of the best possible split (Graham 1969).
// O(C log C) time and O(C) memory for C configurations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"

namespace psweep {

struct CostModel {
  // Defaults for an engine without a declared cost_ns, per sub-step on one thread: brute's and
  // auto's figures (engines.cpp), so that an older psim's estimate stays in the same range.
  double pair_step_s = 0.35e-9;
  double particle_step_s = 100e-9;
  // psim's start, its scene drawn and its metrics written (6-9 ms on the machine of engines.cpp),
  // and psweep's bookkeeping of the run (1 ms: the threads baseline's sweep_wall_s less its
  // children's time, over its 144 runs).
  double process_s = 0.01;
  // What a program's run adds: its confinement's start (bwrap: 25 ms a run on that machine in
  // configs/programs_example.json) and its share of psim check's judging of its output.
  double program_s = 0.04;
  // What a run of P ranks adds, on the 2-core AMD EPYC VM while other builds shared it: the
  // launcher's start and MPI's set-up in every rank (mpirun -np 1 and 2 start in 0.27 and
  // 0.33 s), and each sub-step's messages (the mpi engine at P = 2 on 20 particles: 7 to 60 us a
  // sub-step with 2 to 5 other tasks running; its P = 1 run 3 to 5 us).
  double launch_s = 0.3;
  double rank_step_s = 50e-6;
  // A program's configuration on a perf-mode scene also has its judging run: the scene in print
  // mode, once (docs/programs.md, "The check").
  std::int64_t cpus = 0;  // CPUs the run's threads share; 0: as many as T
  // A program of N^2 growth without a cost_ns of its own is costed as a straightforward one: the
  // lab's plain C reference, plain_allpairs at -O2 since its cheap rejection (docs/programs.md,
  // "The reference"), 1.18 s on the 2019 scene (N = 1000, S = 1000, T = 1: 1.2 ns per N^2 per
  // sub-step) on the 2-core Intel Xeon VM at f8c5d89, 2.6 to 3.2 times faster than before (when
  // this was 3.1 ns). A slower program is under-estimated, a faster one over-estimated; grade
  // prices each submission from its own judging runs (analysis/grade/estimate.py).
  double program_pair_step_s = 1.2e-9;
};

// The particles a broad phase meets around a particle in a sub-step: those inside the square of side
// 3 d around it (a cell at least d wide and the cells beside it), d = s + 2 v / K, the distance two
// particles of the scene's mean speed v close in a sub-step (the random scene's speed range, its
// default where the config gives none: L / (8 r) to L / 4), capped at the N - 1 others; the cost
// model charges an engine's neighbour_ns for each. For an
// engine of G x G cells (one that uses G), those in the cells it scans, every cell within the
// reach of the largest speed: (2 ceil(d / (L / G)) + 1)^2 cells; and at least those cells, each
// costing about what a particle in it does (at G = 64 on the section-8 scene: 361 cells scanned
// for 176 particles).
double reach_neighbours(const Params& params);

// Estimated seconds of one repetition of `params` for `engine`.
double estimate_run_s(const Params& params, const EngineFacts& engine, const CostModel& model = {});

// Shard I of N, numbered from 1 as Slurm's --array=1-N numbers its tasks.
struct ShardSpec {
  int index = 1;
  int count = 1;
};

// Parses "I/N" (1 <= I <= N); throws ConfigError saying what is wrong.
ShardSpec parse_shard(const std::string& text);
std::string to_string(const ShardSpec& shard);  // "I/N"

// The 0-based shard of each configuration, costs[i] being configuration i's total cost.
std::vector<int> partition(const std::vector<double>& costs, int shards);

// Estimated seconds of a configuration of `config`: its warm-ups and repetitions, with what a
// program's confinement and check add.
double configuration_s(const Config& config, const Declaration& declaration, const Params& params,
                       const CostModel& model = {});

// The 0-based shard of each configuration of `config`, in expansion order: the partition of their
// costs. psweep --shard and psweep merge both use it. One lazy pass; 12 bytes per configuration.
std::vector<int> assign_shards(const Config& config, const Declaration& declaration, int shards);

}  // namespace psweep
