// Size of a sweep: see size.hpp.
#include "config/size.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "config/expansion.hpp"

namespace psweep {
namespace {

// An estimate's precision: "0.4 s", "40 s", "12 min", "5.1 h", "3.2 days"; a tenth of a second
// below 10 s, so that the engines of a short sweep still compare.
std::string rough_duration(double s) {
  if (s < 10) return fmt::format("{:.1f} s", s);
  if (s < 90) return fmt::format("{:.0f} s", s);
  if (s < 5400) return fmt::format("{:.0f} min", s / 60);
  if (s < 2 * 86400) return fmt::format("{:.1f} h", s / 3600);
  return fmt::format("{:.1f} days", s / 86400);
}

}  // namespace

SweepSize measure(const Config& config, const Declaration& declaration,
                  const std::function<bool(std::size_t)>& keep, const CostModel& model) {
  SweepSize size;
  size.cpus = model.cpus;
  std::size_t index = 0;
  for_each_configuration(config, declaration, [&](const Params& p) {
    if (!keep(index++)) return;
    const double s = configuration_s(config, declaration, p, model);
    for (SweepSize::Tally* t : {&size.engines[p.engine], &size.total}) {
      ++t->configurations;
      t->seconds += s;
    }
    size.largest_T = std::max(size.largest_T, p.T.value_or(1));
    size.largest_P = std::max(size.largest_P, p.P.value_or(0));
  });
  return size;
}

std::string size_report(const Config& c, const SweepSize& size) {
  const auto reps = static_cast<std::size_t>(c.repetitions);
  std::string text =
      fmt::format("{:<14} {:>14} {:>16} {:>14}\n", "engine", "configurations", "runs", "estimate");
  auto line = [&](const std::string& name, const SweepSize::Tally& t) {
    text += fmt::format("{:<14} {:>14} {:>16} {:>14}\n", name, t.configurations,
                        t.configurations * reps, rough_duration(t.seconds));
  };
  for (const auto& [engine, tally] : size.engines) line(engine, tally);
  line("total", size.total);
  const std::string machine =
      size.cpus > 0 ? fmt::format("on this machine's {} CPU{} (more threads take turns)", size.cpus,
                                  size.cpus == 1 ? "" : "s")
                    : "on one machine with ideal speed-up";
  text += fmt::format(
      "{} configurations x {} repetitions = {} runs (+ {} warm-up runs); the estimate is the cost "
      "model's, {}\n",
      size.total.configurations, c.repetitions, size.total.configurations * reps,
      size.total.configurations * static_cast<std::size_t>(c.warmup), machine);
  if (size.largest_P > 0) text += fmt::format("largest P: {}\n", size.largest_P);
  text += fmt::format("largest T: {}\n", size.largest_T);
  return text;
}

void check_size(const Config& c, std::size_t configurations, double seconds, bool confirmed,
                const std::string& what) {
  const auto runs = static_cast<std::int64_t>(configurations) * c.repetitions;
  if (confirmed || runs <= c.max_runs) return;
  const std::string estimate =
      seconds < 0 ? ""
                  : fmt::format("; at the cost model's estimate they take {} on one machine",
                                rough_duration(seconds));
  throw ConfigError(fmt::format(
      "{}: {} has {} runs ({} configurations x {} repetitions), more than max_runs = {}{}. Split "
      "it over a cluster (psweep --shard I/N, make sweep-slurm), or go ahead with --yes or "
      "\"max_runs\": {} in the config",
      c.file, what, runs, configurations, c.repetitions, c.max_runs, estimate, runs));
}

}  // namespace psweep
