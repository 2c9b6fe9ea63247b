// Plan: see plan.hpp.
#include "sweep/plan.hpp"

#include <fmt/format.h>

#include "config/program.hpp"
#include "run/confine.hpp"

namespace psweep {
namespace {

// A sweep with runs of P ranks starts them through its launcher: one that cannot be executed is
// the config's error, before anything runs, not a failed row per run.
void check_launcher(const Plan& plan) {
  if (plan.size.largest_P == 0) return;
  const Config& c = plan.config;
  const std::string& first = c.launcher.front();
  if (const auto why = cannot_execute(resolve_executable(first)))
    throw ConfigError(fmt::format(
        "{}: {}: cannot execute \"{}\": {} (the runs of P ranks start through it{})", c.file,
        c.raw.contains("launcher") ? "launcher[0]" : "launcher", first, *why,
        c.raw.contains("launcher") ? "" : "; this is the default, mpirun: install OpenMPI or set "
                                          "\"launcher\""));
}

}  // namespace

bool Plan::in_shard(std::size_t index) const {
  return !shard || shard_of[index] == shard->index - 1;
}

Plan make_plan(Config config, Declaration declaration, std::optional<ShardSpec> shard,
               std::int64_t cpus) {
  Plan plan{std::move(config), std::move(declaration), shard, {}, {}, "the sweep"};
  if (shard) {
    plan.shard_of = assign_shards(plan.config, plan.declaration, shard->count);
    plan.what = "shard " + to_string(*shard);
  }
  plan.size = measure(
      plan.config, plan.declaration, [&](std::size_t i) { return plan.in_shard(i); },
      CostModel{.cpus = cpus});
  check_launcher(plan);
  return plan;
}

void print_dry_run(const Plan& plan, bool count, std::FILE* out) {
  const Config& c = plan.config;
  if (count) {
    if (plan.shard) fmt::print(out, "{} of {}\n", plan.what, c.file);
    fmt::print(out, "{}", size_report(c, plan.size));
    return;
  }
  std::size_t index = 0;
  for_each_configuration(c, plan.declaration, [&](const Params& p) {
    if (plan.in_shard(index++)) fmt::print(out, "{}\n", describe(make_run(c, p)));
  });
  const std::size_t n = plan.size.total.configurations;
  fmt::print(
      out,
      "{} configurations x {} repetitions = {} runs (+ {} warm-up runs), pin {}, timeout {:g} "
      "s\n",
      n, c.repetitions, n * static_cast<std::size_t>(c.repetitions),
      n * static_cast<std::size_t>(c.warmup), to_string(c.pin), c.timeout_s);
}

std::vector<RunSpec> planned_runs(const Plan& plan, bool confirmed) {
  check_size(plan.config, plan.size.total.configurations, plan.size.total.seconds, confirmed,
             plan.what);
  return expand(plan.config, plan.declaration, [&](std::size_t i) { return plan.in_shard(i); });
}

std::filesystem::path results_folder(const Plan& plan, const std::optional<std::string>& out_dir) {
  if (out_dir) return *out_dir;
  return "results/" + plan.config.name +
         (plan.shard ? fmt::format("/shard-{}", plan.shard->index) : "");
}

}  // namespace psweep
