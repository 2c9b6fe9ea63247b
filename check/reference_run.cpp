#include "reference_run.hpp"

#include <algorithm>

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

}  // namespace

ReferenceRun::ReferenceRun(const Scene& scene, const StepRules& rules)
    : scene_(scene), rules_(rules), last_(scene.particles) {
  std::fill(last_.pair_collisions.begin(), last_.pair_collisions.end(), 0);
  std::fill(last_.wall_collisions.begin(), last_.wall_collisions.end(), 0);
}

const Particles& ReferenceRun::next() {
  if (at_ == states_.size()) run_chunk();
  return states_[at_++];
}

void ReferenceRun::run_chunk() {
  // x, y, vx, vy and two counts per particle, per time unit kept.
  const std::size_t bytes = std::max<std::size_t>(1, scene_.size() * 6 * 8);
  const auto fits = static_cast<std::int64_t>(std::max<std::size_t>(1, kMaxChunkBytes / bytes));
  chunk_ = std::min({std::max<std::int64_t>(1, 2 * chunk_), kMaxChunk, fits,
                     std::max<std::int64_t>(1, scene_.steps - done_)});
  Scene run;
  run.L = scene_.L;
  run.r = scene_.r;
  run.steps = chunk_;
  run.mode = scene_.mode;
  run.particles = last_;
  RunOptions options;
  options.threads = 1;
  options.slow_factor = rules_.slow_factor;
  options.wall_stop = rules_.wall_stop;
  states_.clear();
  at_ = 0;
  simulate(run, options, [&](std::int64_t, const Particles& p) { states_.push_back(p); });
  states_.push_back(std::move(run.particles));
  // Counts so far in the chunk, each time unit's made its own, newest first.
  for (std::size_t k = states_.size(); k-- > 1;) counts_since(states_[k], states_[k - 1]);
  last_ = states_.back();
  std::fill(last_.pair_collisions.begin(), last_.pair_collisions.end(), 0);
  std::fill(last_.wall_collisions.begin(), last_.wall_collisions.end(), 0);
  done_ += chunk_;
}

}  // namespace particle::check
