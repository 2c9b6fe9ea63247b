// psweep CONFIG [--out DIR] [--resume [--force]] [--dry-run [--count]] [--shard I/N] [--yes]
//   [--psim PATH] [--unconfined]
// psweep merge OUT SHARD_DIR... [--replace]
// psweep confined [--stdout FILE] [--stdout-bytes B] [--timeout-s S] [--unconfined] -- COMMAND...
// The command line only.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstring>

#include "results/merge.hpp"
#include "sweep/confined.hpp"
#include "sweep/sweep.hpp"
#include "usage_error.hpp"

namespace {

int parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s\n", app.get_name().c_str(),
                 lab::usage_message(e, app.get_name()).c_str());
    return 2;
  }
  return -1;
}

std::vector<std::string> words(int argc, char** argv) { return {argv, argv + argc}; }

int merge_main(int argc, char** argv) {
  psweep::MergeOptions opt;
  CLI::App app{
      "psweep merge: join the shard folders of one sweep (psweep CONFIG --shard I/N) into OUT "
      "(runs.csv, summary.csv, meta.json); exit 1 when runs are missing or duplicated"};
  app.name("psweep merge");
  app.add_option("OUT", opt.out, "merged results folder")->required();
  app.add_option("SHARD_DIR", opt.shard_dirs, "shard folders, e.g. results/big/shard-*")
      ->required();
  app.add_flag("--replace", opt.replace,
               "OUT already holds results: move them to OUT/previous/ and merge anew");
  if (int rc = parse(app, argc, argv); rc >= 0) return rc;
  opt.command_line = words(argc + 1, argv - 1);
  return psweep::run_merge(opt);
}

int confined_main(int argc, char** argv) {
  psweep::ConfinedOptions opt;
  CLI::App app{
      "psweep confined: one command run as a submission's program is, in a sandbox, under the "
      "default limits (what make grade builds sources with); exit status: the command's, 124 "
      "when it timed out"};
  app.name("psweep confined");
  app.add_option("COMMAND", opt.command, "the command and its arguments (after --)")->required();
  app.add_option("--stdout", opt.stdout_path, "its stdout (default /dev/null)");
  app.add_option("--stdout-bytes", opt.stdout_bytes,
                 "the most bytes any file it writes may hold (RLIMIT_FSIZE; default none)");
  app.add_option("--timeout-s", opt.timeout_s, "wall-clock limit (default 120)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--unconfined", opt.unconfined, "run it as you, with no sandbox");
  if (int rc = parse(app, argc, argv); rc >= 0) return rc;
  return psweep::run_confined(opt);
}

}  // namespace

int main(int argc, char** argv) {
  // A subcommand by position: a config file named "merge" is still ./merge.
  if (argc > 1 && std::strcmp(argv[1], "merge") == 0) return merge_main(argc - 1, argv + 1);
  if (argc > 1 && std::strcmp(argv[1], "confined") == 0)
    return confined_main(argc - 1, argv + 1);
  psweep::SweepOptions opt;
  CLI::App app{
      "psweep: run a sweep of psim configurations and write runs.csv, summary.csv and meta.json\n"
      "  psweep merge OUT SHARD_DIR...   joins the shards of a sweep (psweep merge --help)\n"
      "  psweep confined -- COMMAND...   one command in a sandbox (psweep confined --help)"};
  app.name("psweep");
  app.add_option("CONFIG", opt.config_path, "sweep config (JSON), e.g. configs/quick.json")
      ->required();
  app.add_option("--out", opt.out_dir,
                 "results directory (default results/<config name>, or results/<config "
                 "name>/shard-I with --shard)");
  app.add_option("--psim", opt.psim, "psim executable (default $PSIM, else psim next to psweep)");
  auto* resume =
      app.add_flag("--resume", opt.resume, "run only the repetitions missing from DIR/runs.csv");
  app.add_flag("--force", opt.force,
               "with --resume: go on although the config expands to other configurations than "
               "the folder's sweep")
      ->needs(resume);
  auto* dry_run = app.add_flag("--dry-run", opt.dry_run,
                               "print the expanded configurations and their count; run nothing");
  app.add_flag("--count", opt.count,
               "with --dry-run: only the counts and estimated time per engine, and the largest T")
      ->needs(dry_run);
  app.add_option("--shard", opt.shard,
                 "run only shard I of N (1 <= I <= N): a cost-balanced part of the "
                 "configurations, all repetitions of each; psweep merge joins the shards");
  app.add_flag("--yes", opt.yes, "go ahead with more runs than the config's max_runs (100000)");
  app.add_flag("--unconfined", opt.unconfined,
               "run the config's external programs as you, in this folder, with your environment "
               "and network (default: each in a sandbox, docs/programs.md)");
  app.add_option("--counters", opt.counters,
                 "hardware (perf events where the machine has them), or simulate: each psim "
                 "configuration once more under cachegrind for the counters the hardware lacks "
                 "(overrides the config's counters)")
      ->check(CLI::IsMember({"hardware", "simulate"}));
  if (int rc = parse(app, argc, argv); rc >= 0) return rc;
  opt.command_line = words(argc, argv);
  return psweep::run_sweep(opt);
}
