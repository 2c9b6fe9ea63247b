#include "reference_run.hpp"

#include <algorithm>
#include <cstring>

#include "particle/simulation.hpp"

namespace particle::check {

namespace {

constexpr std::int64_t kMaxChunk = 64;
constexpr std::size_t kMaxChunkBytes = std::size_t{64} << 20;

// One time unit's counts alone: `now`'s less `before`'s.
void counts_since(Particles& now, const Particles& before) {
  for (std::size_t i = 0; i < now.size(); ++i) {
    now.pair_collisions[i] -= before.pair_collisions[i];
    now.wall_collisions[i] -= before.wall_collisions[i];
  }
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// The same state to the bit (a -0 is not a 0 here: it may print as "-0.00000000").
bool same_state(const Particles& a, const Particles& b) {
  return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.vx, b.vx) &&
         same_bits(a.vy, b.vy) && same_bits(a.pair_collisions, b.pair_collisions) &&
         same_bits(a.wall_collisions, b.wall_collisions);
}

}  // namespace

States SharedChunks::run(const Scene& scene, const StepRules& rules, const Particles& start,
                         std::int64_t length, bool every_unit) {
  for (const Chunk& c : last_) {
    const bool parted = (c.rules.wall_stop != rules.wall_stop && c.wall_stops > 0) ||
                        (c.rules.overlap != rules.overlap && c.receding_overlaps > 0);
    if (c.rules.slow_factor == rules.slow_factor && c.length == length &&
        c.every_unit == every_unit && !parted && same_state(c.start, start))
      return c.states;
  }
  Scene run;
  run.L = scene.L;
  run.r = scene.r;
  run.steps = length;
  run.mode = scene.mode;
  run.particles = start;
  RunOptions options;
  options.threads = 1;
  options.slow_factor = rules.slow_factor;
  options.wall_stop = rules.wall_stop;
  options.overlap = rules.overlap;
  auto states = std::make_shared<std::vector<Particles>>();
  const RunReport report = simulate(run, options, [&](std::int64_t, const Particles& p) {
    if (every_unit) states->push_back(p);
  });
  states->push_back(std::move(run.particles));
  // Counts so far in the chunk, each time unit's made its own, newest first.
  if (every_unit)
    for (std::size_t k = states->size(); k-- > 1;) counts_since((*states)[k], (*states)[k - 1]);
  Chunk chunk{rules, start, length, every_unit, report.counters.receding_overlaps,
              report.counters.wall_stops, std::move(states)};
  const auto same_reading = std::find_if(last_.begin(), last_.end(), [&](const Chunk& c) {
    return c.rules.wall_stop == rules.wall_stop && c.rules.overlap == rules.overlap &&
           c.rules.slow_factor == rules.slow_factor && c.every_unit == every_unit;
  });
  if (same_reading == last_.end()) return last_.emplace_back(std::move(chunk)).states;
  *same_reading = std::move(chunk);
  return same_reading->states;
}

ReferenceRun::ReferenceRun(const Scene& scene, const StepRules& rules, SharedChunks& shared)
    : scene_(scene), rules_(rules), shared_(shared), last_(scene.particles) {
  std::fill(last_.pair_collisions.begin(), last_.pair_collisions.end(), 0);
  std::fill(last_.wall_collisions.begin(), last_.wall_collisions.end(), 0);
}

const Particles& ReferenceRun::next() {
  if (!states_ || at_ == states_->size()) run_chunk();
  return (*states_)[at_++];
}

void ReferenceRun::run_chunk() {
  // x, y, vx, vy and two counts per particle, per time unit kept.
  const std::size_t bytes = std::max<std::size_t>(1, scene_.size() * 6 * 8);
  const auto fits = static_cast<std::int64_t>(std::max<std::size_t>(1, kMaxChunkBytes / bytes));
  chunk_ = std::min({std::max<std::int64_t>(1, 2 * chunk_), kMaxChunk, fits,
                     std::max<std::int64_t>(1, scene_.steps - done_)});
  states_ = shared_.run(scene_, rules_, last_, chunk_, true);
  at_ = 0;
  last_ = states_->back();
  std::fill(last_.pair_collisions.begin(), last_.pair_collisions.end(), 0);
  std::fill(last_.wall_collisions.begin(), last_.wall_collisions.end(), 0);
  done_ += chunk_;
}

}  // namespace particle::check
