#pragma once
// The working state of one run, shared by every stage. Velocities are kept per sub-step
// (u = v / K, exact because K is a power of two), so stages never multiply by dt.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "host_device.hpp"
#include "particle/replay.hpp"  // Candidate

namespace particle::detail {

struct World {
  std::size_t n = 0;
  double L = 0, r = 0;
  double s = 0, s2 = 0;   // contact distance 2r and its square
  double lo = 0, hi = 0;  // wall lines: centres stay in [lo, hi] = [r, L-r]
  double* x = nullptr;
  double* y = nullptr;
  double* ux = nullptr;  // displacement per sub-step
  double* uy = nullptr;
  std::uint64_t* pair_collisions = nullptr;
  std::uint64_t* wall_collisions = nullptr;
  // Momentum each particle gave the walls, the sum of 2 |u_normal| (unit mass, in u's unit): kept
  // per particle so that the total, summed in particle order after the run (simulate()), is the
  // same for every thread count, split and slot order.
  double* wall_impulse = nullptr;
  // The particle held in each slot of the arrays above when a run keeps them in cell order
  // (broad_phase/cell_order.hpp); nullptr: slot i holds particle i. Stages index slots; only the
  // collision order's tie-breaks and a pair's orientation use the particles' ids.
  std::uint32_t* id = nullptr;
  // Whether the cells broad phase may put the arrays above, id with them, in another order at a
  // build, between two sub-steps (broad_phase/cells.hpp, resort()): set only by the runs that hold
  // one shared state in cell order (broad_phase/cell_order.hpp), whose order nothing outside the
  // loop reads until the callback or the end has put it back by id.
  bool reorderable = false;
  // The wall-stop reading (particle::WallStop): after a collision, a wall line stops the whole
  // motion instead of the crossing coordinate alone (contact.hpp's move_rest).
  bool whole_motion = false;
  // The overlap reading (particle::Overlap): a pair overlapping at a sub-step's start collides at
  // t = 0 even while it recedes (narrow_phase.hpp's take_receding).
  bool overlaps_collide = false;
};

// The particle in slot i.
inline std::uint32_t particle_id(const std::uint32_t* id, std::uint32_t i) {
  return id ? id[i] : i;
}

// `w` over other arrays of its particles (a thread's copy, a rank's slots): every other field,
// the box and the model's reading included, stays w's, but for reorderable.
inline World over_arrays(const World& w, std::size_t n, double* x, double* y, double* ux,
                         double* uy, std::uint64_t* pair_collisions, std::uint64_t* wall_collisions,
                         double* wall_impulse) {
  World moved = w;
  moved.n = n;
  moved.x = x;
  moved.y = y;
  moved.ux = ux;
  moved.uy = uy;
  moved.pair_collisions = pair_collisions;
  moved.wall_collisions = wall_collisions;
  moved.wall_impulse = wall_impulse;
  moved.reorderable = false;  // a copy's or a rank's order is its owner's to keep
  return moved;
}

// f(a) on each of w's per-particle arrays (all but id): what a change of the slots' order moves.
template <class F>
void for_each_particle_array(const World& w, F&& f) {
  f(w.x);
  f(w.y);
  f(w.ux);
  f(w.uy);
  f(w.pair_collisions);
  f(w.wall_collisions);
  f(w.wall_impulse);
}

// A World over arrays of n particles owned by the caller; u is the displacement per sub-step.
inline World make_world(double L, double r, std::size_t n, double* x, double* y, double* ux,
                        double* uy, std::uint64_t* pair_collisions, std::uint64_t* wall_collisions,
                        double* wall_impulse) {
  World box;
  box.L = L;
  box.r = r;
  box.s = 2 * r;
  box.s2 = box.s * box.s;
  box.lo = r;
  box.hi = L - r;
  return over_arrays(box, n, x, y, ux, uy, pair_collisions, wall_collisions, wall_impulse);
}

// Per-thread output of the candidate stages; padded so threads never share a cache line.
struct alignas(64) ThreadScratch {
  std::vector<Candidate> candidates;
  std::vector<double> wall_time;  // find_wall_candidates' vector pass, per particle
  std::vector<std::uint32_t> wall_kind;
  std::uint64_t pair_tests = 0;
  std::uint64_t overlaps = 0;
  // The overlapping pairs that recede, this sub-step's, as candidates at t = 0 (the overlap
  // reading `always` collides them: take_receding), and their count over the run: where the two
  // overlap readings part.
  std::vector<Candidate> receding;
  std::uint64_t receding_overlaps = 0;
  // Collided particles whose rest of the sub-step a wall line cut (contact.hpp's move_rest): where
  // the two wall-stop readings part.
  std::uint64_t wall_stops = 0;
  double max_overlap = 0;  // deepest overlap found, relative to s

  // Before a sub-step's candidates.
  void clear_candidates() {
    candidates.clear();
    receding.clear();
  }
};

}  // namespace particle::detail
