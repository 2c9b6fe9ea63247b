// Plan: the first stage of a sweep. What it will run, decided before anything is written: the
// config, psim's declaration, the shard's configurations and the sweep's size, the --dry-run
// listing or counts, the max_runs guard, and the results folder.
//
// Pure apart from the printing: it takes the declaration as given (sweep.cpp asks psim), so a test
// can plan against any declaration.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "config/shard.hpp"
#include "config/size.hpp"

namespace psweep {

struct Plan {
  Config config;
  Declaration declaration;         // empty when psim could not be asked (a dry run only)
  std::optional<ShardSpec> shard;  // --shard I/N
  std::vector<int> shard_of;       // each configuration's 0-based shard; empty without --shard
  SweepSize size;                  // of the shard's configurations
  std::string what;                // "the sweep" or "shard I/N", for messages

  // Whether the configuration at this position of the expansion belongs to the shard.
  bool in_shard(std::size_t index) const;
};

// Partitions the configurations (with a shard) and measures the shard's size, its estimate for a
// machine with `cpus` CPUs (0: as many as T; the split itself never depends on them): one or two
// lazy passes over the expansion. Throws ConfigError for a run that cannot be formed.
Plan make_plan(Config config, Declaration declaration, std::optional<ShardSpec> shard,
               std::int64_t cpus = 0);

// --dry-run: the shard's configurations one line each, streamed (a listing of 10^7 lines holds
// one at a time), and the count line; with `count`, only the size table per engine.
void print_dry_run(const Plan& plan, bool count, std::FILE* out);

// The shard's runs. Throws ConfigError, saying how long they would take, when they exceed the
// config's max_runs and `confirmed` (--yes) is not set.
std::vector<RunSpec> planned_runs(const Plan& plan, bool confirmed);

// --out, else results/<name>, or results/<name>/shard-I for a shard.
std::filesystem::path results_folder(const Plan& plan, const std::optional<std::string>& out_dir);

}  // namespace psweep
