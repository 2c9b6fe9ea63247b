#include "sweep/sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "config/shard.hpp"
#include "config/size.hpp"
#include "results/ceilings.hpp"
#include "results/csv.hpp"
#include "results/folder.hpp"
#include "results/meta.hpp"
#include "results/results.hpp"
#include "run/command.hpp"
#include "run/runner.hpp"
#include "run/tier.hpp"
#include "sweep/finish.hpp"
#include "sweep/plan.hpp"
#include "sweep/resume.hpp"
#include "sweep/run_loop.hpp"
#include "sweep/schedule.hpp"
#include "sweep/simulate.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The config's programs whose output numbers sub-steps ("numbers": "sub-steps").
std::vector<std::string> sub_steps_numbered(const Config& config) {
  std::vector<std::string> names;
  for (const Program& program : config.programs)
    if (program.sub_steps_numbered) names.push_back(program.facts.name);
  return names;
}

std::string default_psim() {
  if (const char* env = std::getenv("PSIM"); env && *env) return env;
  std::error_code ec;
  auto self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("psim") : (self.parent_path() / "psim").string();
}

// psim's declaration; without a psim only a dry run goes on (with an empty declaration, which
// leaves every axis in).
Declaration declaration_of(const std::string& psim, bool psim_ok) {
  if (!psim_ok) return {};
  try {
    return ask_psim(psim);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
}

// What a confined program must not see even where the system's folders hold it: the working
// folder (the repository), the results and psim's folder.
std::vector<std::string> hidden_folders(const fs::path& out, const std::string& psim) {
  std::vector<std::string> folders;
  std::error_code ec;
  for (const fs::path& p : {fs::current_path(ec), out, fs::path(psim).parent_path()})
    if (auto real = fs::weakly_canonical(fs::absolute(p, ec), ec); !ec) folders.push_back(real);
  return folders;
}

// --dry-run: the listing or the counts; `missing_psim` names a psim that was not found.
int dry_run(const Plan& plan, bool count, const std::string& missing_psim) {
  print_dry_run(plan, count, stdout);
  if (!missing_psim.empty())
    std::fprintf(stderr,
                 "psweep: warning: %s not found; engine names not checked and no axis left out "
                 "(psim --describe says which parameters each engine uses)\n",
                 missing_psim.c_str());
  return 0;
}

// How the config's external programs run confined: the strongest tier the machine allows
// (run/tier.hpp), said in one line where it is not the first; none without programs or with
// --unconfined. Before anything is written, a sweep that cannot confine them does not start.
std::unique_ptr<Tier> choose_tier(const Config& config, bool unconfined,
                                  const std::vector<std::string>& hide) {
  if (config.programs.empty() || unconfined) return nullptr;
  std::string why;
  auto tier = strongest_tier(hide, why);
  if (!tier)
    throw UsageError(fmt::format(
        "cannot confine the config's external programs: {}; or run them unconfined, as you and "
        "with your files and network, with --unconfined",
        why));
  if (!why.empty())
    std::fprintf(stderr, "psweep: programs run confined by %s, without namespaces (%s)\n",
                 tier->name().c_str(), why.c_str());
  return tier;
}

// This session's meta.json (build_meta's), with the shard and the programs' confinement.
Json sweep_meta(const MetaInputs& mi, const Plan& plan, std::size_t runs, Tier* tier) {
  Json meta = build_meta(mi);
  if (plan.shard)
    meta["shard"] = {{"index", plan.shard->index},
                     {"count", plan.shard->count},
                     {"configurations", runs},
                     {"estimate_s", plan.size.total.seconds}};
  if (tier)
    meta["confinement"] = {{"tool", tier->name()},
                           {"user", geteuid() == 0 ? "nobody" : "the user running psweep"},
                           {"sandbox_start_s", tier->start_s()}};
  else if (!plan.config.programs.empty())
    meta["confinement"] = {{"tool", "none (--unconfined)"}};
  return meta;
}

// counters: "simulate", the config's or --counters': refused where valgrind cannot run here.
bool simulation_wanted(const SweepOptions& opt, const Config& config) {
  const bool simulate = opt.counters ? *opt.counters == "simulate" : config.simulate_counters;
  if (simulate)
    if (const std::string why = cannot_simulate(); !why.empty())
      throw UsageError(fmt::format("{}: counters: \"simulate\": {}",
                                   opt.counters ? "--counters" : config.file, why));
  return simulate;
}

// Said once per sweep where nothing counts instructions, and what would.
constexpr const char* kNoHardware =
    "psweep: no hardware perf events here: cycles, instructions, branches, branch_misses and "
    "cache_misses stay empty (counters: \"simulate\" in the config, or --counters simulate, "
    "counts instructions and misses under cachegrind)\n";

// The stages in order: plan (plan.hpp), resume (resume.hpp), the run loop (run_loop.hpp), finish
// (finish.hpp). meta.json is written once here as the sweep starts, and again by finish.
int sweep(const SweepOptions& opt) {
  if (opt.out_dir && opt.out_dir->empty()) throw UsageError("--out: expected a folder, got \"\"");
  Config config = load_config(opt.config_path);
  std::optional<ShardSpec> shard;
  if (opt.shard) shard = parse_shard(*opt.shard);
  const std::string psim = opt.psim.value_or(default_psim());
  const bool psim_ok = access(psim.c_str(), X_OK) == 0;
  Declaration declaration = declaration_of(psim, psim_ok);
  if (psim_ok) check_engines(config, declaration.engine_names(), declaration.unavailable);
  // Counted without the walk first: measuring a product of 10^9 configurations takes minutes,
  // and without --yes they are refused anyway (a shard's own count is checked after the walk).
  if (!opt.dry_run && !opt.yes && !shard)
    check_size(config, count_configurations(config, declaration), -1, false, "the sweep");
  const int cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  const Plan plan = make_plan(std::move(config), std::move(declaration), shard, cores);

  const bool simulate = simulation_wanted(opt, plan.config);
  if (opt.dry_run) return dry_run(plan, opt.count, psim_ok ? "" : psim);
  const std::vector<RunSpec> runs = planned_runs(plan, opt.yes);
  if (!psim_ok)
    throw UsageError(
        fmt::format("psim not found or not executable: {} (use --psim PATH or PSIM=)", psim));
  const fs::path out = results_folder(plan, opt.out_dir);
  const std::unique_ptr<Tier> tier =
      choose_tier(plan.config, opt.unconfined, hidden_folders(out, psim));
  const FolderLock lock(out);  // until the sweep ends: two sweeps in one folder spoil both
  const std::string meta_json = (out / "meta.json").string();
  std::optional<Json> earlier = opt.resume ? earlier_meta(meta_json) : std::nullopt;
  if (earlier && !opt.force)
    check_same_expansion(*earlier, plan.config, plan.declaration, meta_json);

  Resumed resumed = resume_or_set_aside(out, opt.resume, runs, runs_columns(plan.declaration));
  if (resumed.foreign)
    std::fprintf(stderr,
                 "psweep: warning: %zu rows of %s belong to configurations not in %s (kept, not "
                 "summarized)\n",
                 resumed.foreign, (out / "runs.csv").c_str(), plan.config.file.c_str());

  MetaInputs mi{&plan.config,     psim,  &plan.declaration, opt.command_line,
                probe_counters(), cores, machine_ceilings()};
  if (!mi.counters.hardware && !simulate) std::fputs(kNoHardware, stderr);
  Json fresh = sweep_meta(mi, plan, runs.size(), tier.get());
  fresh["counters"]["simulated"] = simulate ? Json(cachegrind_options()) : Json(nullptr);
  if (!fs::exists(meta_json)) earlier.reset();  // set aside: nothing to resume after all
  Json meta = continued_meta(fresh, earlier, out.string());
  write_json(meta_json, meta);

  const auto jobs = make_schedule(runs.size(), plan.config.repetitions, plan.config.warmup,
                                  schedule_seed, [&](std::size_t run, int rep) {
                                    return resumed.done.count({runs[run].id, rep}) > 0;
                                  });
  std::vector<std::string> inputs = write_inputs(runs, out);
  std::vector<ProgramScene> scenes = write_program_scenes(plan.config, runs, inputs, out, psim);
  LoopSetup setup{&plan.config,
                  &plan.declaration,
                  &runs,
                  std::move(inputs),
                  out,
                  cores,
                  node_name(),
                  std::move(scenes),
                  psim_judge(psim, plan.config.timeout_s, plan.config.reading,
                             sub_steps_numbered(plan.config)),
                  {}};
  install_interrupt_handlers();
  if (simulate)
    setup.simulated = simulate_counters(plan.config, runs, jobs, setup.inputs, out.string(), psim);
  const std::string resume = resume_command(plan.config.file, shard, out);
  try {
    const LoopTotals totals = run_loop(
        setup, jobs, child_launcher(plan.config, psim, &mi.counters, tier.get()), resumed.recorded);
    return finish_sweep(meta, meta_json, totals, interrupt_signal(), resume, out);
  } catch (const std::exception& e) {  // a full disk, most likely: the rows written are whole
    std::fprintf(stderr,
                 "psweep: error: %s\npsweep: the finished rows are kept; once the cause is "
                 "fixed (room on the disk), continue with:\n  %s\n",
                 e.what(), resume.c_str());
    return 1;
  }
}

}  // namespace

int run_sweep(const SweepOptions& opt) {
  try {
    return sweep(opt);
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "psweep: %s\n", e.what());
    return 2;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "psweep: %s\n", e.what());
    return 2;
  } catch (const FolderBusy& e) {
    std::fprintf(stderr, "psweep: %s\n", e.what());
    return 2;
  } catch (const ResultsError& e) {
    std::fprintf(stderr, "psweep: %s; use another --out\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "psweep: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace psweep
