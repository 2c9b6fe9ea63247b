// Declaration: psim's description of itself (`psim --describe`), read once per sweep.
//
// psweep names no engine and no metric: which parameters an engine uses (so expansion leaves out
// the axes it ignores) and which metrics a run reports (so runs.csv has a column per metric, in
// psim's order) come from here. meta.json keeps the JSON so the analysis reads the same facts.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"

namespace psweep {

struct EngineFacts {
  std::string name;
  std::vector<std::string> uses;  // parameter keys: "T", "G", "slow_factor"
  // The power of N that one sub-step's work grows with: 1 ("N": cells, a sort, events) or 2
  // ("N^2": every pair); 1 when not declared. The cost model (shard.hpp) reads it, so psweep names
  // no engine.
  int growth = 1;
  // Nanoseconds of one sub-step per unit of growth on one thread ("cost_ns"); 0 when not declared
  // (an older psim, or a program), and the cost model then uses its default for the growth.
  double cost_ns = 0;
  bool uses_param(const std::string& key) const;
};

enum class MetricType { real, count, flag };

struct MetricFacts {
  std::string key;      // --metrics key and runs.csv column
  std::string section;  // the --metrics object holding it; empty = top level
  std::string kind;     // stage_time, counter, physics, status
  MetricType type = MetricType::real;
};

struct Declaration {
  std::vector<std::string> params;  // the parameter keys some engine may ignore
  std::vector<EngineFacts> engines;
  std::vector<MetricFacts> metrics;
  Json json;  // as psim printed it, for meta.json

  // nullptr for an unknown engine (or when psim could not be asked: a dry run without psim).
  const EngineFacts* engine(const std::string& name) const;
  std::vector<std::string> engine_names() const;
};

// Parses `psim --describe` output. Throws std::runtime_error saying what is wrong.
Declaration parse_declaration(const std::string& text);

// Runs `psim --describe` and parses it; throws std::runtime_error naming psim when it fails.
Declaration ask_psim(const std::string& psim);

}  // namespace psweep
