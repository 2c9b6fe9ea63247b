// Shard: see shard.hpp for the cost model and the partition's guarantees.
#include "config/shard.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <functional>
#include <numeric>
#include <queue>

#include "particle/random_scene.hpp"

namespace psweep {

namespace {

// Seconds of one sub-step per unit of growth: the engine's declared figures, else the model's.
double unit_s(const Params& p, const EngineFacts& engine, const CostModel& m) {
  if (engine.cost_ns > 0) {
    const double neighbours = engine.growth == 2 ? 0 : engine.neighbour_ns * reach_neighbours(p);
    return (engine.cost_ns + neighbours) * 1e-9;
  }
  if (engine.growth != 2) return m.particle_step_s;
  return engine.program ? m.program_pair_step_s : m.pair_step_s;
}

}  // namespace

double reach_neighbours(const Params& p) {
  if (p.N < 2 || p.L <= 0) return 0;
  const particle::SpeedRange range = p.speed_min && p.speed_max
                                         ? particle::SpeedRange{*p.speed_min, *p.speed_max}
                                         : particle::default_speed_range(p.L, p.r);
  const double k = static_cast<double>(p.slow_factor.value_or(1));
  const double others = static_cast<double>(p.N - 1);
  if (!p.G) {
    const double reach = 2 * p.r + (range.min + range.max) / k;  // two of the mean speed
    return others * std::min(1.0, (3 * reach) * (3 * reach) / (p.L * p.L));
  }
  // G x G cells, each particle scanning the cells within the reach of the largest speed.
  const double side = p.L / static_cast<double>(*p.G);
  const double reach = 2 * p.r + 2 * range.max / k;
  const double across = 2 * std::ceil(reach / side) + 1;
  const double scanned = std::min(p.L, across * side);
  const double cells = std::min(across, static_cast<double>(*p.G));  // per side
  return std::max(others * scanned * scanned / (p.L * p.L), cells * cells);
}

double estimate_run_s(const Params& p, const EngineFacts& engine, const CostModel& m) {
  const double n = static_cast<double>(p.N);
  const double sub_steps =
      static_cast<double>(p.S) * static_cast<double>(p.slow_factor.value_or(1));
  const std::int64_t threads = run_threads(p);  // P ranks share the work as T threads do
  const double parallel =
      static_cast<double>(m.cpus > 0 ? std::min<std::int64_t>(threads, m.cpus) : threads);
  const double units = engine.growth == 2 ? n * n : n;
  const double ranks = p.P ? m.launch_s + m.rank_step_s * sub_steps : 0;
  return m.process_s + ranks + unit_s(p, engine, m) * units * sub_steps / parallel;
}

ShardSpec parse_shard(const std::string& text) {
  auto bad = [&](const char* why) {
    return ConfigError(
        fmt::format("--shard {}: {} (expected I/N with 1 <= I <= N, e.g. 2/8)", text, why));
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw bad("no '/'");
  auto number = [&](std::string_view part) {
    int value = 0;
    auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (ec != std::errc() || end != part.data() + part.size() || part.empty())
      throw bad("not two integers");
    return value;
  };
  ShardSpec s{number(std::string_view(text).substr(0, slash)),
              number(std::string_view(text).substr(slash + 1))};
  if (s.count < 1) throw bad("N must be at least 1");
  if (s.index < 1 || s.index > s.count) throw bad("I must be between 1 and N");
  return s;
}

std::string to_string(const ShardSpec& s) { return fmt::format("{}/{}", s.index, s.count); }

std::vector<int> partition(const std::vector<double>& costs, int shards) {
  std::vector<std::size_t> order(costs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return costs[a] > costs[b]; });
  // (load, shard) pairs, the lightest on top; equal loads go to the lowest shard.
  using Load = std::pair<double, int>;
  std::priority_queue<Load, std::vector<Load>, std::greater<>> lightest;
  for (int s = 0; s < shards; ++s) lightest.push({0.0, s});
  std::vector<int> shard_of(costs.size(), 0);
  for (std::size_t i : order) {
    auto [load, s] = lightest.top();
    lightest.pop();
    shard_of[i] = s;
    lightest.push({load + costs[i], s});
  }
  return shard_of;
}

double configuration_s(const Config& config, const Declaration& declaration, const Params& params,
                       const CostModel& model) {
  const EngineFacts* engine = declaration.runnable(config, params.engine);
  const EngineFacts facts = engine ? *engine : EngineFacts{};
  const bool judged =
      facts.program && !(config.scene && config.scene->mode == particle::OutputMode::print);
  return (config.repetitions + config.warmup + (judged ? 1 : 0)) *
         ((facts.program ? model.program_s : 0) + estimate_run_s(params, facts, model));
}

std::vector<int> assign_shards(const Config& config, const Declaration& declaration, int shards) {
  std::vector<double> costs;
  for_each_configuration(config, declaration, [&](const Params& p) {
    costs.push_back(configuration_s(config, declaration, p));
  });
  return partition(costs, shards);
}

}  // namespace psweep
