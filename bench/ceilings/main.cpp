// ceilings: this machine's ceilings as one JSON object (docs/performance.md, "The machine's
// ceilings"): on stdout, or with --out FILE written whole there, into the cache psweep reads
// (results/ceilings.hpp), and a short table on stdout. psweep runs it once per machine and build
// (meta.json's "ceilings") where the cache has none; `make ceilings` measures afresh.
// --exit and --team are its own children: an empty process, and a first OpenMP team.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "measure.hpp"
#include "particle/io.hpp"
#include "results/ceilings.hpp"
#include "startup.hpp"
#include "usage_error.hpp"
#include "whole_file.hpp"

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--exit") return 0;
  if (argc == 3 && std::string(argv[1]) == "--team") {
    std::printf("%.9g\n", ceilings::first_team_s(std::stoi(argv[2])));
    return 0;
  }
  CLI::App app{
      "ceilings: this machine's ceilings (pair kernel, bandwidth, caches, start-up) as JSON"};
  app.name("ceilings");
  std::string out;
  ceilings::Options options;
  app.add_option("--out", out, "write the JSON here (whole) and print a short table");
  app.add_option("--repetitions", options.repetitions, "timings of each figure (default 7)")
      ->check(CLI::Range(1, 1000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "ceilings: %s\n", lab::usage_message(e, "ceilings").c_str());
    return 2;
  }
  std::error_code ec;
  options.self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec) options.self = argv[0];
  try {
    std::optional<lab::WholeFile> file;
    if (!out.empty()) file.emplace(out, "--out");  // a bad path fails before minutes of timing
    const nlohmann::json ceilings = ceilings::measure(options);
    if (!file) {
      std::fputs((ceilings.dump(2) + "\n").c_str(), stdout);
      return 0;
    }
    // A person's measurement: psweep's sweeps record it from now on.
    const nlohmann::json stamped =
        psweep::cache_ceilings(ceilings, options.self, psweep::ceilings_cache(options.self));
    std::fputs((stamped.dump(2) + "\n").c_str(), file->get());
    file->commit();
    std::fputs(ceilings::table(ceilings).c_str(), stdout);
    return 0;
  } catch (const particle::InputError& e) {
    std::fprintf(stderr, "ceilings: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ceilings: error: %s\n", e.what());
    return 1;
  }
}
