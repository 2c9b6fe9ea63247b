#include "measure.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "bandwidth.hpp"
#include "pair_kernel.hpp"
#include "run/caches.hpp"
#include "spread.hpp"
#include "startup.hpp"

namespace ceilings {
namespace {

using Json = nlohmann::json;
using psweep::Cache;
using psweep::data_cache_bytes;
using psweep::read_caches;

std::string first_line(const char* path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "";
}

std::uint64_t available_bytes() {
  std::ifstream in("/proc/meminfo");
  for (std::string key; in >> key;) {
    std::uint64_t kib = 0;
    in >> kib;
    if (key == "MemAvailable:") return kib << 10;
    in.ignore(1 << 10, '\n');
  }
  return std::uint64_t{1} << 30;
}

Json caches_json(const std::vector<Cache>& caches) {
  Json list = Json::array();
  for (const Cache& c : caches)
    list.push_back({{"level", c.level},
                    {"type", c.type},
                    {"size_bytes", c.size_bytes},
                    {"line_bytes", c.line_bytes},
                    {"ways", c.ways},
                    {"shared_cpu_list", c.shared_cpu_list}});
  return list;
}

// The passes that take about `seconds` on one thread.
int calibrate_passes(std::uint32_t n, double seconds) {
  for (int passes = 1;; passes *= 2) {
    const KernelTiming t = time_kernel(n, passes, 1);
    if (t.seconds >= seconds / 4 || passes >= (1 << 24))
      return std::max(1, static_cast<int>(passes * seconds / std::max(t.seconds, 1e-9)));
  }
}

// T = 1 and all CPUs in turn, round by round, so that the ratio of a round compares two timings
// seconds apart.
Json pair_kernel(const Options& o, std::uint64_t l1_bytes, int cpus) {
  const std::uint32_t n = particles_for_l1(l1_bytes);
  const int passes = calibrate_passes(n, o.kernel_s);
  const std::uint64_t per_pass = std::uint64_t{n} * (n - 1) / 2;
  std::vector<double> one, all, ratio;
  for (int rep = 0; rep < o.repetitions; ++rep) {
    double ns[2];
    for (int k = 0; k < 2; ++k) {
      const int threads = k == 0 ? 1 : cpus;
      const KernelTiming t = time_kernel(n, passes, threads);
      // The engine's own counter says what ran: a kernel that skipped pairs would look fast.
      if (t.count.pair_tests != per_pass * passes * threads || t.count.candidates != 0)
        throw std::logic_error("the pair kernel did not test every pair of its scene once");
      ns[k] = t.seconds * 1e9 / static_cast<double>(t.count.pair_tests);
    }
    one.push_back(ns[0]);
    all.push_back(ns[1]);
    ratio.push_back(ns[0] / ns[1]);
  }
  return {{"particles", n},
          {"scene_bytes", n * 4 * sizeof(double)},
          {"pair_tests_per_timing", per_pass * passes},
          {"vector_bits", vector_bits()},
          {"T1", {{"threads", 1}, {"ns_per_pair_test", to_json(spread_of(one))}}},
          {"Tall", {{"threads", cpus}, {"ns_per_pair_test", to_json(spread_of(all))}}},
          {"rate_ratio", to_json(spread_of(ratio))}};
}

Json bandwidth(const Options& o, std::uint64_t llc_bytes, int cpus) {
  Arrays arrays(elements_for(llc_bytes, available_bytes()), cpus);
  triad(arrays, 3.0, cpus);    // warm: pages mapped, the team up
  std::vector<double> gbs[4];  // triad T1, triad Tall, memcpy T1, memcpy Tall
  for (int rep = 0; rep < o.repetitions; ++rep)
    for (int k = 0; k < 4; ++k) {
      const int threads = k % 2 == 0 ? 1 : cpus;
      const Moved m = k < 2 ? triad(arrays, 3.0, threads) : copy(arrays, threads);
      gbs[k].push_back(static_cast<double>(m.bytes) / m.seconds / 1e9);
    }
  const std::uint64_t working_set = 3 * arrays.elements() * sizeof(double);
  auto pair = [&](int k) {
    return Json{{"T1", {{"threads", 1}, {"gb_per_s", to_json(spread_of(gbs[k]))}}},
                {"Tall", {{"threads", cpus}, {"gb_per_s", to_json(spread_of(gbs[k + 1]))}}}};
  };
  return {{"array_bytes", arrays.elements() * sizeof(double)},
          {"working_set_bytes", working_set},
          {"beyond_llc", llc_bytes > 0 && working_set > llc_bytes},
          {"bytes_per_element", {{"triad", 24}, {"memcpy", 16}}},
          {"triad", pair(0)},
          {"memcpy", pair(2)}};
}

// The start of an empty process (this program, linked as psim is, exiting at once) and beside it
// psim's own (issue 58), where a psim is beside this program: `psim --list-engines` (the loader,
// the static set-up, the command line) and a whole run of one particle (scenes/corner.in's scene,
// brute at T = 1: the scene read, 3 time units, the output). The programs alternate, so that each
// sees the same load.
void process_starts(const Options& o, Json& out) {
  const std::string psim = (std::filesystem::path(o.self).parent_path() / "psim").string();
  const bool with_psim = access(psim.c_str(), X_OK) == 0;
  const std::filesystem::path scene =
      std::filesystem::temp_directory_path() / fmt::format("ceilings-corner-{}.in", getpid());
  std::vector<std::vector<std::string>> runs = {{o.self, "--exit"}};
  if (with_psim) {
    std::ofstream(scene) << "1\n10\n1\n3\nprint\n0 5 5 4 4\n";
    runs.push_back({psim, "--list-engines"});
    runs.push_back({psim, "--engine", "brute", "--threads", "1", scene.string()});
  }
  std::vector<std::vector<double>> seconds(runs.size());
  try {
    for (int rep = 0; rep < 3 * o.repetitions; ++rep)
      for (std::size_t k = 0; k < runs.size(); ++k)
        seconds[k].push_back(time_processes(runs[k], 1).front());
  } catch (...) {
    std::filesystem::remove(scene);
    throw;
  }
  std::filesystem::remove(scene);
  out["process_s"] = to_json(spread_of(seconds[0]));
  if (!with_psim) return;
  out["psim_list_engines_s"] = to_json(spread_of(seconds[1]));
  out["psim_one_particle_s"] = to_json(spread_of(seconds[2]));
}

Json startup(const Options& o, int cpus) {
  std::vector<double> regions;
  for (int rep = 0; rep < o.repetitions; ++rep) regions.push_back(warm_region_s(cpus, 200));
  Json out = {{"omp_team_s", to_json(spread_of(child_figures(
                                 {o.self, "--team", std::to_string(cpus)}, 3 * o.repetitions)))},
              {"omp_region_s", to_json(spread_of(regions))},
              {"threads", cpus}};
  process_starts(o, out);
  return out;
}

}  // namespace

Json measure(const Options& o) {
  const auto start = std::chrono::steady_clock::now();
  const int cpus = omp_get_num_procs();
  const std::vector<Cache> caches = read_caches();
  const std::uint64_t l1 = data_cache_bytes(caches, 1);
  Json out;
  out["ceilings_version"] = 1;
  out["cpu_model"] = cpu_model();
  out["cpus"] = cpus;
  out["loadavg_before"] = first_line("/proc/loadavg");
  out["caches"] = caches_json(caches);
  out["pair_kernel"] = pair_kernel(o, l1 ? l1 : 32 << 10, cpus);
  out["bandwidth"] = bandwidth(o, data_cache_bytes(caches, 0), cpus);
  out["startup"] = startup(o, cpus);
  out["loadavg_after"] = first_line("/proc/loadavg");
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

std::string table(const Json& c) {
  const int cpus = c["cpus"];
  std::string text = fmt::format(
      "ceilings of {} ({} CPUs, {}-bit pair kernel), {:.1f} s, load "
      "average {} -> {}\n",
      c["cpu_model"].get<std::string>(), cpus, c["pair_kernel"]["vector_bits"].get<int>(),
      c["seconds"].get<double>(), c["loadavg_before"].get<std::string>().substr(0, 4),
      c["loadavg_after"].get<std::string>().substr(0, 4));
  text += fmt::format("  {:<40} {:>10} {:>10} {:>10}\n", "", "min", "median", "max");
  auto row = [&](const std::string& what, const Json& s, double scale) {
    text += fmt::format("  {:<40} {:>10.4g} {:>10.4g} {:>10.4g}\n", what,
                        s["min"].get<double>() * scale, s["median"].get<double>() * scale,
                        s["max"].get<double>() * scale);
  };
  const Json& k = c["pair_kernel"];
  row("pair test, T=1 (ns)", k["T1"]["ns_per_pair_test"], 1);
  row(fmt::format("pair test, T={} (ns, all threads)", cpus), k["Tall"]["ns_per_pair_test"], 1);
  row(fmt::format("kernel rate T={} / T=1", cpus), k["rate_ratio"], 1);
  for (const char* kind : {"triad", "memcpy"})
    for (const char* t : {"T1", "Tall"})
      row(fmt::format("{} bandwidth, T={} (GB/s)", kind,
                      c["bandwidth"][kind][t]["threads"].get<int>()),
          c["bandwidth"][kind][t]["gb_per_s"], 1);
  row("process start (ms)", c["startup"]["process_s"], 1e3);
  if (c["startup"].contains("psim_list_engines_s")) {
    row("psim --list-engines (ms)", c["startup"]["psim_list_engines_s"], 1e3);
    row("psim, one particle, T=1 (ms)", c["startup"]["psim_one_particle_s"], 1e3);
  }
  row(fmt::format("OpenMP team start, T={} (ms)", cpus), c["startup"]["omp_team_s"], 1e3);
  row(fmt::format("OpenMP parallel region, T={} (us)", cpus), c["startup"]["omp_region_s"], 1e6);
  text += "  caches:";
  for (const Json& cache : c["caches"])
    text += fmt::format(" L{}{} {} KiB;", cache["level"].get<int>(),
                        cache["type"] == "Data"          ? "d"
                        : cache["type"] == "Instruction" ? "i"
                                                         : "",
                        cache["size_bytes"].get<std::uint64_t>() >> 10);
  if (!c["bandwidth"]["beyond_llc"].get<bool>())
    text +=
        "\n  (the bandwidth's arrays fit in the last-level cache sysfs reports: a cache's "
        "bandwidth, not memory's)";
  return text + "\n";
}

}  // namespace ceilings
