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
  // What a run's `engine` names: the config's program of that name, else psim's engine; nullptr
  // for neither. Expansion, the size and the shards read these facts alone, so a program is
  // described as an engine is.
  const EngineFacts* runnable(const Config& config, const std::string& name) const;
  std::vector<std::string> engine_names() const;
};

// "N" -> 1, "N^2" -> 2; a std::runtime_error "<where>.growth: ..." for anything else.
int parse_growth(const std::string& text, const std::string& where);

// Parses `psim --describe` output. Throws std::runtime_error saying what is wrong.
Declaration parse_declaration(const std::string& text);

}  // namespace psweep
