// Wall candidates: per particle and axis, the fraction of the sub-step at which its centre reaches
// a wall line; the earlier axis wins and equal times are a corner. O(N), independent per particle,
// so any split across threads yields the same set. A particle at rest or sliding along a wall has
// u == 0 on that axis and never counts as a hit (its 0/0 or x/0 is discarded by a select).
//
// Two passes over each chunk, both branch-free (about a fifth of the particles hit a wall
// in a sub-step of the default scene, in no pattern a branch predictor can learn): a vectorized
// pass computes every time and kind with selects (two divisions per particle, 8 lanes at a time),
// and counts the hits, then a compaction pass writes each candidate to the next free slot, which
// only advances on a hit.
#include <algorithm>

#include "contact.hpp"
#include "parallel/team.hpp"
#include "step/stages.hpp"

namespace particle::detail {
namespace {

// Particle (x, y, ux, uy)'s wall hit: the fraction of the sub-step at which its centre first
// reaches a wall line (above 1: none in this sub-step) and which wall.
struct WallHit {
  double time;
  std::uint32_t kind;
};
inline WallHit wall_hit(double x, double y, double ux, double uy, double lo, double hi) {
  const double tx = wall_axis_time(x, ux, lo, hi), ty = wall_axis_time(y, uy, lo, hi);
  return {std::min(tx, ty), wall_kind(tx, ty)};
}

void find_in_range(const World& w, std::size_t lo, std::size_t hi, ThreadScratch& out) {
  const std::size_t count = hi - lo;
  out.wall_time.resize(count);
  out.wall_kind.resize(count);
  double* __restrict time = out.wall_time.data();
  std::uint32_t* __restrict kind = out.wall_kind.data();
  const double* __restrict x = w.x + lo;
  const double* __restrict y = w.y + lo;
  const double* __restrict ux = w.ux + lo;
  const double* __restrict uy = w.uy + lo;
  std::size_t hits = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const WallHit hit = wall_hit(x[k], y[k], ux[k], uy[k], w.lo, w.hi);
    time[k] = hit.time;
    kind[k] = hit.kind;
    hits += hit.time <= 1;
  }
  // Room for the hits and the one slot a miss after the last hit writes: resize() zeroes what it
  // adds, and room for every particle was a memset of 16 bytes a particle and sub-step.
  std::vector<Candidate>& c = out.candidates;
  const std::size_t base = c.size();
  c.resize(base + hits + 1);
  std::size_t used = base;
  for (std::size_t k = 0; k < count; ++k) {
    c[used] = {time[k], static_cast<std::uint32_t>(lo + k), kind[k]};
    used += time[k] <= 1;
  }
  c.resize(used);
}

}  // namespace

void find_wall_candidates_in(const World& w, std::size_t c, ThreadScratch& out) {
  find_in_range(w, c * kWallChunk, std::min(w.n, (c + 1) * kWallChunk), out);
}

void find_wall_candidate(const World& w, std::uint32_t i, ThreadScratch& out) {
  const WallHit hit = wall_hit(w.x[i], w.y[i], w.ux[i], w.uy[i], w.lo, w.hi);
  if (hit.time <= 1) out.candidates.push_back({hit.time, i, hit.kind});
}

void find_wall_candidates(const World& w, ThreadScratch& out) {
  const auto chunks = static_cast<std::uint32_t>((w.n + kWallChunk - 1) / kWallChunk);
  team_for(chunks, [&](std::uint32_t c) { find_wall_candidates_in(w, c, out); });
}

}  // namespace particle::detail
