#pragma once
// The event engine's calendar: an indexed 4-ary min-heap with one slot per particle.
//
// Each particle owns exactly one prediction, its earliest event (pair, wall or cell crossing;
// infinitely late when it has none), kept in events_; the heap orders the particles by it. A new
// prediction replaces the particle's old one in place and moves its slot up or down, so the heap
// holds N entries and never a stale one: a collision re-predicts both of its particles, which
// overwrites every prediction it made wrong except those of third particles that had predicted a
// contact with one of them; such a pair event carries the partner's event counter and is found
// out when it surfaces (event_simulation.cpp re-predicts its owner). This is the "one event per
// particle" scheme of DynamO and of Smallenburg's EDMD; a heap of all predictions with lazy
// deletion (what this replaced) popped about one stale entry per collision and held 1.3 N.
//
// Order: the total order (time, kind, lower particle, higher particle, owner) with input indices,
// walls before pairs before cell crossings at equal times (the discrete model's wall-first rule).
// Live predictions never have equal keys, so the run never depends on how the heap breaks ties.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "world.hpp"

namespace particle::detail {

// Partner codes above every particle index: walls as in world.hpp, then the four cell crossings.
inline constexpr std::uint32_t kCrossXLow = 0xFFFFFFF0u;  // into the cell at x - 1
inline constexpr std::uint32_t kCrossXHigh = 0xFFFFFFF1u;
inline constexpr std::uint32_t kCrossYLow = 0xFFFFFFF2u;
inline constexpr std::uint32_t kCrossYHigh = 0xFFFFFFF3u;
inline constexpr std::uint32_t kFirstCode = kCrossXLow;  // partners below are particles

struct Event {
  double t;                   // absolute time, in time units; infinite: no event
  std::uint32_t owner;        // the particle that predicted it
  std::uint32_t other;        // partner particle, or a wall or crossing code
  std::uint32_t other_count;  // the partner's event counter at prediction (pairs only)

  bool is_pair() const { return other < kFirstCode; }
  bool is_wall() const { return other >= kWallX; }
  // 0 wall, 1 pair, 2 crossing: the order among simultaneous events.
  int rank() const { return is_wall() ? 0 : (is_pair() ? 1 : 2); }
};

// The total order of events. Particles are stored in a spatial order of the engine's own
// (event_simulation.cpp); `id` maps them back to input indices, which break ties.
struct EventOrder {
  const std::uint32_t* id;

  // a strictly before b. Times nearly always differ: the rest of the key is the rare path.
  bool operator()(const Event& a, const Event& b) const {
    if (a.t != b.t) [[likely]]
      return a.t < b.t;
    return tie(a, b);
  }

  [[gnu::noinline]] bool tie(const Event& a, const Event& b) const {
    if (a.rank() != b.rank()) return a.rank() < b.rank();
    const std::uint32_t a_lo = a.is_pair() ? std::min(id[a.owner], id[a.other]) : id[a.owner];
    const std::uint32_t b_lo = b.is_pair() ? std::min(id[b.owner], id[b.other]) : id[b.owner];
    if (a_lo != b_lo) return a_lo < b_lo;
    const std::uint32_t a_hi = a.is_pair() ? std::max(id[a.owner], id[a.other]) : a.other;
    const std::uint32_t b_hi = b.is_pair() ? std::max(id[b.owner], id[b.other]) : b.other;
    if (a_hi != b_hi) return a_hi < b_hi;
    return id[a.owner] < id[b.owner];
  }
};

// The heap's nodes carry the time next to the particle, so a sift compares without touching the
// events; the four children of a node (16 bytes each) fill exactly one cache line.
class EventQueue {
 public:
  // Particles 0 to n - 1, none in the heap yet: add() each once, then set().
  EventQueue(EventOrder earlier, std::uint32_t n)
      : earlier_(earlier), events_(n), slot_(n), lines_((n + kOffset + kArity - 1) / kArity + 1) {
    heap_ = &lines_[0].node[kOffset];
  }
  EventQueue(const EventQueue&) = delete;  // heap_ points into lines_
  EventQueue& operator=(const EventQueue&) = delete;

  bool empty() const { return size_ == 0; }
  const Event& top() const { return events_[heap_[0].p]; }
  EventOrder order() const { return earlier_; }
  const Event& event_of(std::uint32_t p) const { return events_[p]; }

  // Puts particle p into the heap with its first prediction.
  void add(std::uint32_t p, const Event& e) {
    events_[p] = e;
    heap_[size_] = {e.t, p};
    slot_[p] = size_++;
    sift_up(slot_[p]);
  }

  // Replaces p's prediction by e.
  void set(std::uint32_t p, const Event& e) {
    const bool later = !earlier_(e, events_[p]);
    events_[p] = e;
    heap_[slot_[p]].t = e.t;
    if (later)
      sift_down(slot_[p]);
    else
      sift_up(slot_[p]);
  }

 private:
  struct Node {
    double t;
    std::uint32_t p;
  };
  static constexpr std::uint32_t kArity = 4;
  // Slot k lives at node kOffset + k of the aligned lines, so the children 4k + 1 .. 4k + 4
  // start a line.
  static constexpr std::uint32_t kOffset = kArity - 1;
  struct alignas(64) Line {
    Node node[kArity];
  };

  bool before(const Node& a, const Node& b) const {
    if (a.t != b.t) [[likely]]
      return a.t < b.t;
    return earlier_.tie(events_[a.p], events_[b.p]);
  }
  void place(std::uint32_t k, const Node& n) {
    heap_[k] = n;
    slot_[n.p] = k;
  }
  void sift_up(std::uint32_t k) {
    const Node n = heap_[k];
    while (k > 0) {
      const std::uint32_t parent = (k - 1) / kArity;
      if (!before(n, heap_[parent])) break;
      place(k, heap_[parent]);
      k = parent;
    }
    place(k, n);
  }
  void sift_down(std::uint32_t k) {
    const Node n = heap_[k];
    for (;;) {
      const std::uint32_t first = kArity * k + 1;
      if (first >= size_) break;
      std::uint32_t best = first;
      const std::uint32_t end = std::min(first + kArity, size_);
      for (std::uint32_t c = first + 1; c < end; ++c)
        if (before(heap_[c], heap_[best])) best = c;
      if (!before(heap_[best], n)) break;
      place(k, heap_[best]);
      k = best;
    }
    place(k, n);
  }

  EventOrder earlier_;
  std::vector<Event> events_;        // per particle, its prediction
  std::vector<std::uint32_t> slot_;  // per particle, its heap slot
  std::vector<Line> lines_;          // the heap's storage, cache-line aligned
  Node* heap_ = nullptr;             // slot 0, the earliest particle
  std::uint32_t size_ = 0;
};

}  // namespace particle::detail
