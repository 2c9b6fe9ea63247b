// Finish: see finish.hpp.
#include "sweep/finish.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <cstdio>

#include "results/meta.hpp"
#include "results/results.hpp"
#include "sweep/progress.hpp"

namespace psweep {

double own_cpu_s() {
  struct rusage self {};
  getrusage(RUSAGE_SELF, &self);
  return static_cast<double>(self.ru_utime.tv_sec + self.ru_stime.tv_sec) +
         static_cast<double>(self.ru_utime.tv_usec + self.ru_stime.tv_usec) / 1e6;
}

Json session_entry(const LoopTotals& t, double harness_cpu_s, const std::string& date) {
  return {
      {"date", date},
      {"jobs", t.finished},
      {"sweep_wall_s", t.wall_s},
      {"children_process_s", t.children_s},
      {"checks_s", t.checks_s},
      {"overhead", t.children_s > 0 ? (t.wall_s - t.children_s - t.checks_s) / t.children_s : 0.0},
      {"harness_cpu_s", harness_cpu_s}};
}

std::string resume_command(const std::string& config_file, const std::optional<ShardSpec>& shard,
                           const std::filesystem::path& out) {
  return fmt::format("psweep {}{} --out {} --resume", config_file,
                     shard ? " --shard " + to_string(*shard) : "", out.string());
}

int finish_sweep(Json& meta, const std::string& meta_json, const LoopTotals& totals, int signal,
                 const std::string& resume_command, const std::filesystem::path& out) {
  // The harness's own cost, for the <= 2% budget: everything but the children's lifetimes.
  const Json cost = session_entry(totals, own_cpu_s(), utc_now());
  meta["sessions"].push_back(cost);
  write_json(meta_json, meta);
  std::fprintf(stderr,
               "psweep: %zu runs in %s (harness overhead %.2f%%), %zu not ok; results in %s\n",
               totals.finished, format_duration(totals.wall_s).c_str(),
               100 * cost["overhead"].get<double>(), totals.not_ok, out.c_str());
  if (!signal) return 0;
  std::fprintf(stderr,
               "psweep: interrupted by signal %d; finished rows are kept. Continue with:\n"
               "  %s\n",
               signal, resume_command.c_str());
  return 128 + signal;
}

}  // namespace psweep
