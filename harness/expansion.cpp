// Expansion: see expansion.hpp for the rules.
#include "expansion.hpp"

#include <fmt/format.h>

#include <unordered_set>

namespace psweep {
namespace {

std::uint64_t fnv1a64(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char ch : text) {
    h ^= ch;
    h *= 1099511628211ULL;
  }
  return h;
}

// Validates combinations that single values cannot show; `file` prefixes messages.
void check_run(const Params& p, const Declaration& d, const std::string& file) {
  if (const EngineFacts* engine = d.engine(p.engine))
    for (const std::string& key : engine->uses)
      if (!(p.*optional_param(key)))
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
}

}  // namespace

void drop_ignored(Params& p, const Declaration& d) {
  const EngineFacts* engine = d.engine(p.engine);
  if (!engine) return;
  for (const std::string& key : d.params)
    if (!engine->uses_param(key)) (p.*optional_param(key)).reset();
}

std::string canonical_text(const Params& p, const std::string& scene_file, Pin pin) {
  return fmt::format(
      "engine={};N={};L={};r={};S={};slow_factor={};T={};G={};seed={};speed_min={};speed_max={};"
      "scene_file={};pin={}{}",
      p.engine, p.N, p.L, p.r, p.S, cell(p.slow_factor), cell(p.T), cell(p.G), cell(p.seed),
      cell(p.speed_min), cell(p.speed_max), scene_file, to_string(pin),
      p.neighbour == "none" ? "" : ";neighbour=" + p.neighbour);  // quiet runs keep their ids
}

std::string config_id(const Params& p, const std::string& scene_file, Pin pin) {
  return fmt::format("{:012x}", fnv1a64(canonical_text(p, scene_file, pin)) >> 16);
}

std::vector<RunSpec> expand(const Config& c, const Declaration& d) {
  std::vector<Params> combos;
  auto apply = [](Params& p, const Axis& axis, std::size_t i) {
    set_param(p, axis.key, axis.values[i], axis.key);  // already validated at parse time
  };
  if (c.sweep.empty()) {
    combos.push_back(c.base);
  } else if (c.combine == Combine::product) {
    std::vector<std::size_t> digit(c.sweep.size(), 0);
    for (;;) {
      Params p = c.base;
      for (std::size_t a = 0; a < c.sweep.size(); ++a) apply(p, c.sweep[a], digit[a]);
      combos.push_back(std::move(p));
      std::size_t a = c.sweep.size();
      while (a > 0 && ++digit[a - 1] == c.sweep[a - 1].values.size()) digit[--a] = 0;
      if (a == 0) break;
    }
  } else if (c.combine == Combine::zip) {
    // Equal lengths are checked at parse time.
    for (std::size_t i = 0; i < c.sweep.front().values.size(); ++i) {
      Params p = c.base;
      for (const auto& axis : c.sweep) apply(p, axis, i);
      combos.push_back(std::move(p));
    }
  } else {
    for (const auto& axis : c.sweep)
      for (std::size_t i = 0; i < axis.values.size(); ++i) {
        Params p = c.base;
        apply(p, axis, i);
        combos.push_back(std::move(p));
      }
  }

  std::vector<RunSpec> runs;
  std::unordered_set<std::string> seen_text;
  std::unordered_set<std::string> seen_id;
  const std::string scene = c.scene_file.value_or("");
  for (auto& p : combos) {
    drop_ignored(p, d);
    check_run(p, d, c.file);
    auto text = canonical_text(p, scene, c.pin);
    if (!seen_text.insert(text).second) continue;  // duplicate configuration: collapse
    RunSpec run{config_id(p, scene, c.pin), p, scene, c.pin};
    if (!seen_id.insert(run.id).second)  // 48-bit hash: practically never; refuse rather than merge
      throw ConfigError(c.file + ": two configurations hash to the same config_id " + run.id);
    runs.push_back(std::move(run));
  }
  return runs;
}

std::string describe(const RunSpec& run) {
  const auto& p = run.params;
  std::string text =
      fmt::format("{} engine={} N={} L={} r={} S={}", run.id, p.engine, p.N, p.L, p.r, p.S);
  if (p.slow_factor) text += fmt::format(" K={}", *p.slow_factor);
  if (p.T) text += fmt::format(" T={}", *p.T);
  if (p.G) text += fmt::format(" G={}", *p.G);
  if (p.seed) text += fmt::format(" seed={}", *p.seed);
  if (p.speed_min) text += fmt::format(" speed={},{}", *p.speed_min, *p.speed_max);
  if (!run.scene_file.empty()) text += " scene=" + run.scene_file;
  return text;
}

}  // namespace psweep
