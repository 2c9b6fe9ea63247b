// Expansion: see expansion.hpp for the rules.
#include "config/expansion.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <optional>
#include <unordered_set>

#include "particle/describe.hpp"
#include "particle/hash.hpp"
#include "particle/limits.hpp"
#include "particle/options.hpp"

namespace psweep {
namespace {

// Config ids were first published with this offset basis (FNV's with its last digit lost); kept,
// so that existing results directories resume under the same ids.
constexpr std::uint64_t kConfigIdBasis = 1469598103934665603ULL;

// The first of psim's own limits (particle/limits.hpp) this run breaks, if any: the run as psim
// would be asked it (unset parameters are psim's defaults).
std::optional<particle::LimitBreach> limit_breach(const Params& p, const Config& c) {
  const auto as_int = [](std::int64_t v) {
    return static_cast<int>(std::min<std::int64_t>(v, INT_MAX));
  };
  particle::RunRequest run;
  run.header = {p.N, p.L, p.r, p.S, particle::OutputMode::perf};
  // Engine names are psim's, checked against its declaration (check_engines); only the
  // continuous-time engine has limits of its own (box crossings), so for an engine this library
  // does not know, any one it knows stands in.
  run.options.engine =
      particle::find_engine_info(p.engine) ? p.engine : particle::engine_names().front();
  run.options.threads = as_int(p.T.value_or(0));
  if (p.G) run.options.grid = as_int(*p.G);
  run.options.slow_factor = as_int(p.slow_factor.value_or(1));
  run.given = c.scene.get();
  if (p.seed) run.seed = *p.seed;
  if (p.speed_min && p.speed_max) run.speed = particle::SpeedRange{*p.speed_min, *p.speed_max};
  return particle::run_limit_breach(run);
}

// A run's value index in each sweep axis; kBase: the axis was not applied (base's value).
constexpr std::size_t kBase = SIZE_MAX;

// Where a run's value of `key` was set: "sweep.N[1]", "base.N", or "scene_file".
std::string path_of(const std::string& key, const Config& c,
                    const std::vector<std::size_t>& index) {
  for (std::size_t a = 0; a < c.sweep.size(); ++a)
    if (c.sweep[a].key == key && index[a] != kBase)
      return fmt::format("sweep.{}[{}]", key, index[a]);
  const bool from_scene =
      key == "N" || key == "L" || key == "r" || key == "S" || key == "scene_file";
  return c.scene_file && from_scene ? std::string("scene_file") : "base." + key;
}

// Validates combinations that single values cannot show, then psim's own limits, naming the key
// path that set the offending value; `c.file` prefixes messages.
void check_run(const Params& p, const Declaration& d, const Config& c,
               const std::vector<std::size_t>& index) {
  const std::string& file = c.file;
  if (const Program* program = c.program(p.engine);
      program && !program->takes_slow_factor && p.slow_factor != program->slow_factor)
    throw ConfigError(fmt::format(
        "{}: {}: program \"{}\" was built for slow_factor {} (its \"slow_factor\"), this run asks "
        "{}; sweep K in a config of its own, or list \"slow_factor\" in the program's \"uses\"",
        file, path_of("slow_factor", c, index), p.engine, program->slow_factor,
        cell(p.slow_factor)));
  if (const EngineFacts* engine = d.runnable(c, p.engine))
    for (const std::string& key : engine->uses)
      if (optional_param(key) && !(p.*optional_param(key)))
        throw ConfigError(fmt::format("{}: base.{}: required when engine \"{}\" runs (or sweep {})",
                                      file, key, p.engine, key));
  if (p.speed_min.has_value() != p.speed_max.has_value())
    throw ConfigError(file + (p.speed_min ? ": base.speed_max: required together with speed_min"
                                          : ": base.speed_min: required together with speed_max"));
  if (p.speed_min && *p.speed_min > *p.speed_max)
    throw ConfigError(fmt::format("{}: speed_min: {} exceeds speed_max {} in a run", file,
                                  *p.speed_min, *p.speed_max));
  if (p.L < 2 * p.r)
    throw ConfigError(
        fmt::format("{}: L: {} is less than 2r = {} in a run (the box cannot hold a disk)", file,
                    p.L, 2 * p.r));
  if (auto breach = limit_breach(p, c))
    throw ConfigError(fmt::format("{}: {}: {} (psim's limit)", file, path_of(breach->key, c, index),
                                  breach->problem));
}

}  // namespace

void drop_ignored(Params& p, const Declaration& d, const Config& c) {
  const EngineFacts* engine = d.runnable(c, p.engine);
  if (!engine) return;
  for (const std::string& key : param_keys())
    if (optional_param(key) && !engine->uses_param(key)) (p.*optional_param(key)).reset();
  if (!engine->uses_param("wall_stop")) p.wall_stop = kDefaultWallStop;
  if (!engine->uses_param("overlap")) p.overlap = kDefaultOverlap;
}

std::string canonical_text(const Params& p, const std::string& scene_file, Pin pin) {
  return fmt::format(
      "engine={};N={};L={};r={};S={};slow_factor={};T={};G={};seed={};speed_min={};speed_max={};"
      "scene_file={};pin={}{}",
      p.engine, p.N, p.L, p.r, p.S, cell(p.slow_factor), cell(p.T), cell(p.G), cell(p.seed),
      cell(p.speed_min), cell(p.speed_max), scene_file, to_string(pin),
      // quiet runs, those of the default reading and those without ranks keep their ids
      (p.neighbour == "none" ? "" : ";neighbour=" + p.neighbour) +
          (p.wall_stop == kDefaultWallStop ? "" : ";wall_stop=" + p.wall_stop) +
          (p.overlap == kDefaultOverlap ? "" : ";overlap=" + p.overlap) +
          (p.P ? ";P=" + cell(p.P) : ""));
}

std::string config_id(const Params& p, const std::string& scene_file, Pin pin) {
  const std::string text = canonical_text(p, scene_file, pin);
  return fmt::format("{:012x}", particle::fnv1a(text.data(), text.size(), kConfigIdBasis) >> 16);
}

namespace {

void apply(Params& p, const Axis& axis, std::size_t i) {
  set_param(p, axis.key, axis.values[i], axis.key);  // already validated at parse time
}

// first_equal[e][a][d]: for the e-th engine (the e-th value of the engine axis, or base's engine),
// the lowest index of axis a whose value gives the same configuration as index d.
using FirstEqual = std::vector<std::vector<std::vector<std::size_t>>>;

FirstEqual first_equal_values(const Config& c, const Declaration& d, std::size_t engine_axis) {
  const std::size_t engines = engine_axis < c.sweep.size() ? c.sweep[engine_axis].values.size() : 1;
  FirstEqual table(engines);
  for (std::size_t e = 0; e < engines; ++e) {
    Params with_engine = c.base;
    if (engine_axis < c.sweep.size()) apply(with_engine, c.sweep[engine_axis], e);
    for (const Axis& axis : c.sweep) {
      std::vector<std::string> texts;
      std::vector<std::size_t> first(axis.values.size());
      for (std::size_t i = 0; i < axis.values.size(); ++i) {
        Params p = with_engine;
        apply(p, axis, i);
        drop_ignored(p, d, c);
        texts.push_back(canonical_text(p, "", Pin::none));
        first[i] = static_cast<std::size_t>(std::find(texts.begin(), texts.end(), texts[i]) -
                                            texts.begin());
      }
      table[e].push_back(std::move(first));
    }
  }
  return table;
}

// The index of the engine axis, or the number of axes when engine is not swept.
std::size_t engine_axis_of(const Config& c) {
  for (std::size_t a = 0; a < c.sweep.size(); ++a)
    if (c.sweep[a].key == "engine") return a;
  return c.sweep.size();
}

void for_each_product(const Config& c, const Declaration& d,
                      const std::function<void(const Params&)>& visit) {
  const std::size_t axes = c.sweep.size();
  const std::size_t engine_axis = engine_axis_of(c);
  const FirstEqual first = first_equal_values(c, d, engine_axis);
  // Per axis, the indices that are the first of their equals for some engine: the others are
  // never visited, so the odometer steps over them (a config of a few lines can repeat values
  // into 10^9 combinations of which a few thousand are distinct).
  std::vector<std::vector<std::size_t>> candidates(axes);
  for (std::size_t a = 0; a < axes; ++a)
    for (std::size_t i = 0; i < c.sweep[a].values.size(); ++i)
      if (std::any_of(first.begin(), first.end(), [&](const auto& e) { return e[a][i] == i; }))
        candidates[a].push_back(i);

  std::vector<std::size_t> at(axes, 0), digit(axes, 0);  // position in candidates, its index
  Params raw = c.base;  // every axis applied at its current digit; ignored values not yet cleared
  for (std::size_t a = 0; a < axes; ++a) apply(raw, c.sweep[a], 0);
  for (;;) {
    const auto& lowest = first[engine_axis < axes ? digit[engine_axis] : 0];
    bool first_of_duplicates = true;
    for (std::size_t a = 0; a < axes && first_of_duplicates; ++a)
      first_of_duplicates = lowest[a][digit[a]] == digit[a];
    if (first_of_duplicates) {
      Params p = raw;
      drop_ignored(p, d, c);
      check_run(p, d, c, digit);
      visit(p);
    }
    std::size_t a = axes;  // odometer: the last axis moves fastest
    while (a > 0 && ++at[a - 1] == candidates[a - 1].size()) at[--a] = 0;
    if (a == 0) return;
    for (std::size_t changed = a - 1; changed < axes; ++changed) {
      digit[changed] = candidates[changed][at[changed]];
      apply(raw, c.sweep[changed], digit[changed]);
    }
  }
}

}  // namespace

std::size_t count_configurations(const Config& c, const Declaration& d) {
  if (c.sweep.empty() || c.combine != Combine::product) {
    std::size_t count = 0;  // at most as many candidates as the axes have values
    for_each_configuration(c, d, [&](const Params&) { ++count; });
    return count;
  }
  // A combination is visited when each digit is the first of its equals for its engine
  // (for_each_product): per engine value, a product of per-axis counts of such digits.
  const std::size_t engine_axis = engine_axis_of(c);
  const FirstEqual first = first_equal_values(c, d, engine_axis);
  const auto saturating = [](std::size_t a, std::size_t b) {
    return b != 0 && a > SIZE_MAX / b ? SIZE_MAX : a * b;
  };
  std::size_t total = 0;
  for (std::size_t e = 0; e < first.size(); ++e) {
    if (engine_axis < c.sweep.size() && first[e][engine_axis][e] != e) continue;
    std::size_t product = 1;
    for (std::size_t a = 0; a < c.sweep.size(); ++a) {
      if (a == engine_axis) continue;
      std::size_t firsts = 0;
      for (std::size_t i = 0; i < first[e][a].size(); ++i) firsts += first[e][a][i] == i;
      product = saturating(product, firsts);
    }
    total = total > SIZE_MAX - product ? SIZE_MAX : total + product;
  }
  return total;
}

void for_each_configuration(const Config& c, const Declaration& d,
                            const std::function<void(const Params&)>& visit) {
  if (!c.sweep.empty() && c.combine == Combine::product) return for_each_product(c, d, visit);
  // No axis, zip or one-at-a-time: at most as many candidates as the axes have values.
  // Each candidate with the value index it took from each axis.
  std::vector<std::pair<Params, std::vector<std::size_t>>> candidates;
  if (c.sweep.empty()) {
    candidates.push_back({c.base, {}});
  } else if (c.combine == Combine::zip) {
    // Equal lengths are checked at parse time.
    for (std::size_t i = 0; i < c.sweep.front().values.size(); ++i) {
      Params p = c.base;
      for (const auto& axis : c.sweep) apply(p, axis, i);
      candidates.push_back({std::move(p), std::vector<std::size_t>(c.sweep.size(), i)});
    }
  } else {
    for (std::size_t a = 0; a < c.sweep.size(); ++a)
      for (std::size_t i = 0; i < c.sweep[a].values.size(); ++i) {
        Params p = c.base;
        apply(p, c.sweep[a], i);
        std::vector<std::size_t> index(c.sweep.size(), kBase);
        index[a] = i;
        candidates.push_back({std::move(p), std::move(index)});
      }
  }
  std::unordered_set<std::string> seen;
  for (auto& [p, index] : candidates) {
    drop_ignored(p, d, c);
    check_run(p, d, c, index);
    if (seen.insert(canonical_text(p, "", Pin::none)).second) visit(p);
  }
}

RunSpec make_run(const Config& c, const Params& p) {
  const std::string scene = c.scene_file.value_or("");
  return {config_id(p, scene, c.pin), p, scene, c.pin};
}

std::vector<RunSpec> expand(const Config& c, const Declaration& d,
                            const std::function<bool(std::size_t)>& keep) {
  std::vector<RunSpec> runs;
  std::unordered_set<std::string> seen_id;
  std::size_t index = 0;
  for_each_configuration(c, d, [&](const Params& p) {
    if (keep && !keep(index++)) return;
    RunSpec run = make_run(c, p);
    if (!seen_id.insert(run.id).second)  // 48-bit hash: practically never; refuse rather than merge
      throw ConfigError(c.file + ": two configurations hash to the same config_id " + run.id);
    runs.push_back(std::move(run));
  });
  return runs;
}

std::string describe(const RunSpec& run) {
  const auto& p = run.params;
  std::string text =
      fmt::format("{} engine={} N={} L={} r={} S={}", run.id, p.engine, p.N, p.L, p.r, p.S);
  if (p.slow_factor) text += fmt::format(" K={}", *p.slow_factor);
  if (p.wall_stop != kDefaultWallStop) text += " wall_stop=" + p.wall_stop;
  if (p.overlap != kDefaultOverlap) text += " overlap=" + p.overlap;
  if (p.T) text += fmt::format(" T={}", *p.T);
  if (p.P) text += fmt::format(" P={}", *p.P);
  if (p.G) text += fmt::format(" G={}", *p.G);
  if (p.seed) text += fmt::format(" seed={}", *p.seed);
  if (p.speed_min) text += fmt::format(" speed={},{}", *p.speed_min, *p.speed_max);
  if (!run.scene_file.empty()) text += " scene=" + run.scene_file;
  return text;
}

}  // namespace psweep
