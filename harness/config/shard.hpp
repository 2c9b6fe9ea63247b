// Shard: the cost model of a run and a deterministic, cost-balanced split of a sweep's
// configurations over N machines (`psweep CONFIG --shard I/N`, one Slurm array task each).
//
// Cost model (seconds of one run, an estimate for balancing and for "how long would this take"):
//   growth N^2 (every pair tested):  process_s + pair_step_s     * N^2 * S * K / T
//   growth N   (cells, sorts, events): process_s + particle_step_s * N   * S * K / T
// K (slow factor) and T (threads) count as 1 where the engine ignores them; T divides as if the
// speed-up were ideal. The growth is the engine's fact in psim's declaration (`psim --describe`,
// "growth"), so the model names no engine; an engine the declaration does not know counts as N.
// The constants were fitted on the development machine (one core, default random scene); only
// their ratios matter for balancing.
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
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"

namespace psweep {

struct CostModel {
  double pair_step_s = 0.45e-9;   // brute, N = 1000..2000: 0.14 s for N = 1000, S = 300
  double particle_step_s = 1e-6;  // auto/sweep, N = 2000: 0.6 s for S = 300 (3x more at N = 20000)
  double process_s = 0.005;       // starting psim and writing its scene and metrics
};

// Estimated seconds of one repetition of `params` for an engine whose work grows as N^growth.
double estimate_run_s(const Params& params, int growth, const CostModel& model = {});

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

// Estimated seconds of a configuration of `config`: its warm-ups and repetitions.
double configuration_s(const Config& config, const Declaration& declaration, const Params& params);

// The 0-based shard of each configuration of `config`, in expansion order: the partition of their
// costs. psweep --shard and psweep merge both use it. One lazy pass; 12 bytes per configuration.
std::vector<int> assign_shards(const Config& config, const Declaration& declaration, int shards);

}  // namespace psweep
