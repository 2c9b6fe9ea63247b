#include "run/simulated.hpp"

#include <fmt/format.h>

#include <sstream>
#include <vector>

#include "run/caches.hpp"

namespace psweep {
namespace {

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// " --D1=49152,12,64": cachegrind's option for one cache, "" where sysfs lacks a figure.
std::string cache_option(const char* name, const Cache& c) {
  if (c.ways <= 0 || c.line_bytes <= 0) return "";
  std::uint64_t sets = c.size_bytes / (std::uint64_t(c.ways) * c.line_bytes);
  if (sets == 0) return "";
  while (sets & (sets - 1)) sets &= sets - 1;  // the power of two at or below
  return fmt::format(" --{}={},{},{}", name, sets * c.ways * c.line_bytes, c.ways, c.line_bytes);
}

}  // namespace

std::optional<SimulatedCounts> parse_cachegrind(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> events, summary;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("events:", 0) == 0) events = words(line.substr(7));
    if (line.rfind("summary:", 0) == 0) summary = words(line.substr(8));
  }
  if (events.empty() || summary.size() != events.size()) return std::nullopt;
  std::map<std::string, std::uint64_t> value;
  for (std::size_t k = 0; k < events.size(); ++k) value[events[k]] = std::stoull(summary[k]);
  for (const char* needed : {"Ir", "ILmr", "DLmr", "DLmw", "Bcm", "Bim"})
    if (!value.count(needed)) return std::nullopt;
  return SimulatedCounts{value["Ir"], value["ILmr"] + value["DLmr"] + value["DLmw"],
                         value["Bcm"] + value["Bim"]};
}

std::string cachegrind_options(const std::string& sysfs) {
  std::string options = "--cache-sim=yes --branch-sim=yes";
  const std::vector<Cache> caches = read_caches(sysfs);
  const Cache* last = nullptr;
  for (const Cache& c : caches) {
    if (c.level == 1) options += cache_option(c.type == "Instruction" ? "I1" : "D1", c);
    if (c.type != "Instruction" && (!last || c.level > last->level)) last = &c;
  }
  if (last && last->level > 1) options += cache_option("LL", *last);
  return options;
}

std::string simulation_refused() {
#ifdef __AVX512F__
  return "this build uses AVX-512 (-march=native on an AVX-512 CPU), which valgrind 3.19 cannot "
         "decode: run the psweep of a build without it (make regress's build-regress/, or make "
         "build BUILD=DIR AVX512=0)";
#else
  return "";
#endif
}

std::string fill_counters(EventCounts& events, const SimulatedCounts* simulated) {
  if (events.instructions) return "hardware";
  if (!simulated) return "";
  events.instructions = simulated->instructions;
  events.cache_misses = simulated->ll_misses;
  events.branch_misses = simulated->branch_misses;
  return "simulated";
}

}  // namespace psweep
