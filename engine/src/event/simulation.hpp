#pragma once
// The exact event-driven simulation of the lab's disks (engine `event`): every collision in
// continuous time, no sub-steps and no one-collision-per-step rule. The accuracy reference that
// the discrete engines' error is measured against.
//
// Design (the standard one, after Alder and Wainwright, Rapaport, and Isobe's cell method):
// - Particles move on straight lines between events. Each keeps its line (position at a common
//   epoch and velocity), changed only when an event changes its velocity; everyone is brought to
//   a common time only for output. An event costs O(1) particles, not O(N).
// - Each particle owns one prediction, its earliest event: a pair contact (contact_time, the one
//   root arithmetic of contact.hpp), a wall line (wall_axis_time, shared with the
//   discrete wall stage), or leaving its grid cell (event/cells.hpp). The calendar queue
//   (event/queue.hpp) orders the particles by their predictions; a new prediction replaces the
//   particle's old one in place. A pair prediction whose partner has had an event since (its event
//   counter moved) is replaced by a fresh prediction of the owner when it surfaces. Completeness: a
//   pair's contact is always predicted by whichever of the two changed velocity or entered the
//   other's neighbourhood last.
// - Cells at least s wide: a prediction tests only the 9 surrounding cells, so an event costs
//   O(1) pair tests plus O(1) queue work; a crossing tests only the 3 cells it comes next to.
// - Overlap rules as the discrete model: an overlapping, approaching pair collides at once; an
//   overlapping, receding one has no event.
// - Zero-time cascades (a row of touching disks) are ordinary events at the same time, taken in
//   the heap's total order (ties by particle index, so runs are deterministic). They end because
//   a pair that has just collided, and where neither disk has had another event since, cannot
//   meet again on straight lines: that pair is not predicted, so rounding in the exchange (a
//   receding pair computed as barely approaching) cannot ping-pong forever.
// - Walls at r and L - r, corners flip both components (the discrete model's laws, contact.hpp).
// Cost per event: two predictions of ~9 cells (a square root and a division per tested pair) and
// two O(1) queue updates; memory O(N).
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <vector>

#include "event/cells.hpp"
#include "event/queue.hpp"
#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail {

class EventSimulation {
 public:
  // Takes the particles from w (velocities per time unit = w.u * slow_factor) and predicts the
  // first event of each.
  EventSimulation(const World& w, int slow_factor);

  // Processes every event at or before `horizon` (a contact exactly at a whole time unit belongs
  // to the unit that ends there, as in the discrete model), then stands at `horizon`. Checks
  // `stop` before each event: false when a stop request ended it early, at now().
  bool run_until(double horizon, const std::atomic<bool>* stop = nullptr);
  double now() const { return now_; }  // the last event's time, or the last horizon reached

  // Writes every particle's state at time `at` (>= the last event) into w's arrays, with
  // displacements per sub-step again; the simulation's own state is untouched.
  void write_state(double at) const;

  const Counters& counters() const { return counters_; }
  // Sum of 2 |v_normal| over wall collisions so far (unit mass, per time unit in the World's
  // length unit): P = wall_impulse / (4 L t). O(N): for tests.
  double wall_impulse() const;
  // Deepest overlap any prediction found, relative to s: 0 unless the input overlaps (exact
  // dynamics creates none; the discrete engines' figure is taken at step ends instead).
  double max_overlap() const { return max_overlap_; }
  std::size_t cells_per_axis() const { return grid_.cells_per_axis(); }
  // Pair predictions that surfaced after their partner had another event (owner re-predicted).
  std::uint64_t stale_events() const { return stale_; }

 private:
  static constexpr std::uint32_t kNobody = 0xFFFFFFFFu;
  static constexpr double kNever = std::numeric_limits<double>::infinity();

  // A particle's straight line: its position at the epoch (the last horizon reached; extended
  // back along the line, so not necessarily inside the box) and its velocity per time unit. The
  // position at any time t is x + vx (t - epoch), so a prediction needs no local time and writes
  // nothing, and a neighbour costs 32 bytes: two per cache line, in the spatial order.
  struct alignas(32) Body {
    double x, y;
    double vx, vy;
  };
  // What only the particle's own events read, kept in its queue entry (one 32-byte record with
  // its prediction), apart from the bodies that neighbours' predictions stream through.
  struct Own {
    // Events that changed its velocity, low 32 bits (the high ones in its Tally): its pair
    // collisions with the Tally's offset added, so that the dense scenes' pair collisions touch
    // no other per-particle record.
    std::uint32_t count = 0;
    std::uint32_t last_partner = kNobody;  // partner of its last event if a pair, else kNobody
    CellPos cell;                          // for grid_
  };
  // The World's per-particle counters in storage order, touched by wall events and count's
  // carries only (written out by write_state). At N = 100,000 the engine's working set is about
  // the last-level cache, and every byte kept out of it counts.
  struct Tally {
    std::uint64_t count_high = 0;   // count's carries, times 2^32
    std::uint64_t pair_offset = 0;  // pair collisions = count + pair_offset (mod 2^64)
    std::uint64_t wall_collisions = 0;
    double wall_impulse = 0;
  };
  // A particle's earliest wall or pair event as last predicted, when its prediction is a cell
  // crossing (else it is the prediction): a crossing changes neither velocity nor the neighbours
  // left behind, so its prediction only adds the cells newly adjacent (3 of 9) to this one. Kept
  // apart from the queue entry, which it would double, and touched only around crossings.
  struct Kept {
    double t;
    std::uint32_t other, other_count;
  };
  // Counts an event that changed i's velocity.
  void count_event(std::uint32_t i) {
    if (++own(i).count == 0) [[unlikely]]
      tally_[i].count_high += std::uint64_t{1} << 32;
  }
  Own& own(std::uint32_t i) { return queue_.payload(i); }

  // Position at time t on the line (predictions).
  double x_at(const Body& b, double t) const { return b.x + b.vx * (t - epoch_); }
  double y_at(const Body& b, double t) const { return b.y + b.vy * (t - epoch_); }
  // Where the particle is at time t, inside the wall lines (events and output): the clamp only
  // catches rounding, since a real crossing of a wall line is a wall event first.
  struct Place {
    double x, y;
  };
  Place place_at(const Body& b, double t) const {
    return {std::clamp(x_at(b, t), w_.lo, w_.hi), std::clamp(y_at(b, t), w_.lo, w_.hi)};
  }
  // Gives b velocity (vx, vy) from place p at time t on.
  void turn(Body& b, Place p, double vx, double vy, double t) const;
  // Moves the epoch to t (keeps the lines' rounding that of one time unit's extension).
  void rebase(double t);
  // Particle i's earliest event from `now` on; infinitely late if none.
  Event predict(std::uint32_t i, double now);
  // The same after i has crossed into a neighbour cell (`code`) at `now`, from its kept event
  // and the particles of the cells it has come next to.
  Event predict_after_crossing(std::uint32_t i, std::uint32_t code, double now);
  // These two are inlined into the predictions: an Event returned through memory is stored
  // field by field and loaded whole, a store-forwarding stall that cost 14% on dense30.
  //
  // The earlier of `best` and i's earliest contact (at (x, y) now) with near_[0 .. count) (the
  // pair arithmetic of contact.hpp).
  [[gnu::always_inline]] inline Event earliest_contact(std::uint32_t i, double x, double y,
                                                       std::uint32_t count, double now, Event best);
  // The earlier of `best` (i's earliest wall or pair event) and i's next cell crossing; keeps
  // `best` in kept_ when the crossing is earlier.
  [[gnu::always_inline]] inline Event add_crossing(std::uint32_t i, double x, double y, Event best,
                                                   double now);
  void collide_wall(const Event& e);
  void collide_pair(const Event& e);

  World w_;
  int slow_factor_;
  std::vector<std::uint32_t> id_;  // input index of each stored particle (spatial order)
  std::vector<Body> body_;
  std::vector<Tally> tally_;
  std::vector<Kept> kept_;
  double epoch_ = 0;
  CellGrid grid_;
  std::vector<std::uint32_t> near_;  // a prediction's neighbours
  EventQueue<Own> queue_;
  Counters counters_;
  double max_overlap_ = 0;
  std::uint64_t stale_ = 0;
  double now_ = 0;
  // The crowding guard. Events come at times that either stop advancing (two disks pressed
  // between walls: each next collision rounds to now) or advance ever less towards a time they
  // never pass (overlapping disks squeezed between walls 2r apart take a wall hit and a pair
  // collision in turn, each cycle shorter by a fixed ratio: a Zeno sequence). Either way more
  // events fall into one short window of time than any scene the engine can finish has:
  // most_at_once_ (64 n + 1024, more than any contact graph of n disks and four walls allows at
  // one instant) within crowd_width_ of the window's start (2^-30 of the time the largest
  // velocity component takes to cross the box, and at least 2^8 rounding steps of the time). A
  // scene legitimately that busy would need 2^30 x 64 n events per box crossing: it could not
  // end either. crowded() then names the particles and jammed() throws InputError.
  double window_end_ = -1;     // the current window: events at or before this time
  std::uint64_t crowded_ = 0;  // events in it after its first
  std::uint64_t most_at_once_;
  double crowd_width_;
  std::vector<std::uint32_t> crowd_;  // input indices of the particles of the crowding events
  void crowded(const Event& e);
  [[noreturn]] void jammed(double t) const;
  // The slower jam: five disks of radius 3 in a box of 12 (98% of it covered, fuzz_scene's find)
  // took 1.7 thousand events in time unit 1, 5.4 million in unit 2 and 100 million in unit 3,
  // never more than a few in the short window above, at a rate about steady within each time
  // unit (a doubling of the events took twice the time: no Zeno sequence to detect, only work
  // without end: the run passed time 3.1 in 20 s). The budget of one
  // time unit, unit_budget_ = 2^12 (n + 4) (1 + min(c, 4)) events, c the box crossings a particle
  // with all the scene's kinetic energy makes in a time unit (capped: one fast particle beside a
  // jam made fuzz_scene's budget 2^12 x 9 x 550 events, minutes under the sanitizers; a fast gas
  // that dense is refused with the same message), is 4096 collisions per particle and
  // crossing: a gas needs 4 r N / L per crossing (its mean free path L^2 / (4 r N)), 1000 for
  // the million-particle crowd, at most 1.16 L / r at the densest packing of disks. It is spent
  // in a second or two here on a scene of fuzz_scene's size (n <= 48), sanitizers included.
  std::uint64_t unit_budget_;
  [[noreturn]] void too_busy(double horizon) const;
};

// The EngineRun of `event` (engines.cpp): single-threaded; threads, G and the sub-steps of K are
// ignored (K only scales the World's displacements back to velocities).
RunReport run_event(const World& w, const RunOptions& options, const PipelineParams& params);

}  // namespace particle::detail
