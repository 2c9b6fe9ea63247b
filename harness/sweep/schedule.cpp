// Schedule: see schedule.hpp. O(rounds x runs).
#include "sweep/schedule.hpp"

#include <numeric>

#include "particle/random_scene.hpp"

namespace psweep {
namespace {

std::vector<std::size_t> shuffled(std::size_t n, particle::Random& rng) {
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.next() % i]);
  return order;
}

}  // namespace

std::vector<Job> make_schedule(std::size_t runs, int repetitions, int warmup, std::uint64_t seed,
                               const std::function<bool(std::size_t, int)>& done) {
  // The engine's portable generator (std::shuffle's use of an engine is unspecified).
  particle::Random rng(seed);
  std::vector<bool> needs_run(runs, false);
  for (std::size_t i = 0; i < runs; ++i)
    for (int rep = 0; rep < repetitions && !needs_run[i]; ++rep) needs_run[i] = !done(i, rep);

  std::vector<Job> jobs;
  for (int w = 0; w < warmup; ++w)
    for (std::size_t i : shuffled(runs, rng))
      if (needs_run[i]) jobs.push_back({i, w, true});
  for (int rep = 0; rep < repetitions; ++rep)
    for (std::size_t i : shuffled(runs, rng))
      if (!done(i, rep)) jobs.push_back({i, rep, false});
  return jobs;
}

}  // namespace psweep
