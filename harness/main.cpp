// psweep CONFIG [--out DIR] [--resume] [--dry-run] [--psim PATH]: the command line only.
#include <CLI/CLI.hpp>

#include "sweep.hpp"

int main(int argc, char** argv) {
  psweep::SweepOptions opt;
  CLI::App app{
      "psweep: run a sweep of psim configurations and write runs.csv, summary.csv and meta.json"};
  app.add_option("CONFIG", opt.config_path, "sweep config (JSON), e.g. configs/quick.json")
      ->required();
  app.add_option("--out", opt.out_dir, "results directory (default results/<config name>)");
  app.add_option("--psim", opt.psim, "psim executable (default $PSIM, else psim next to psweep)");
  app.add_flag("--resume", opt.resume, "run only the repetitions missing from DIR/runs.csv");
  app.add_flag("--dry-run", opt.dry_run,
               "print the expanded configurations and their count; run nothing");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }
  for (int i = 0; i < argc; ++i) opt.command_line.emplace_back(argv[i]);
  return psweep::run_sweep(opt);
}
