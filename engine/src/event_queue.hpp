#pragma once
// The event engine's calendar: predicted events in a binary min-heap, stale ones dropped lazily.
//
// Each particle owns at most one live prediction, its earliest event (pair, wall or cell
// crossing); a pair event is also live for the partner. Instead of deleting predictions that a
// collision makes wrong (O(N) search or an indexed heap), every event carries the event counters
// its particles had when it was predicted; a collision bumps the counters of its particles, and
// an event whose counters no longer match is stale and skipped when it reaches the top. Each
// collision leaves at most a few stale entries, so the heap stays O(N) and push/pop cost O(log N).
//
// Order: the total order (time, kind, lower particle, higher particle, owner) with input indices,
// walls before pairs before cell crossings at equal times (the discrete model's wall-first rule).
// Equal keys cannot have different effects, so the run never depends on how the heap breaks ties.
#include <algorithm>
#include <cstdint>
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
  double t;                                // absolute time, in time units
  std::uint32_t owner;                     // the particle that predicted it
  std::uint32_t other;                     // partner particle, or a wall or crossing code
  std::uint32_t owner_count, other_count;  // event counters at prediction (other: pairs only)

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

// A 4-ary min-heap: half the depth of a binary heap, and the four children of a node share two
// cache lines, so a pop (the deepest walk) takes about half the cache misses. The order is
// inlined (a function pointer passed to std::push_heap was not: 20% of the run time).
class EventQueue {
 public:
  explicit EventQueue(EventOrder earlier) : earlier_(earlier) {}
  void reserve(std::size_t n) { heap_.reserve(n); }
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }
  const Event& top() const { return heap_.front(); }
  EventOrder order() const { return earlier_; }

  void push(const Event& e) {
    std::size_t k = heap_.size();
    heap_.push_back(e);
    while (k > 0) {
      const std::size_t parent = (k - 1) / kArity;
      if (!earlier_(e, heap_[parent])) break;
      heap_[k] = heap_[parent];
      k = parent;
    }
    heap_[k] = e;
  }

  Event pop() {
    const Event top = heap_.front();
    const Event last = heap_.back();
    heap_.pop_back();
    const std::size_t n = heap_.size();
    if (n == 0) return top;
    std::size_t k = 0;
    for (;;) {
      const std::size_t first = kArity * k + 1;
      if (first >= n) break;
      std::size_t best = first;
      const std::size_t end = std::min(first + kArity, n);
      for (std::size_t c = first + 1; c < end; ++c)
        if (earlier_(heap_[c], heap_[best])) best = c;
      if (!earlier_(heap_[best], last)) break;
      heap_[k] = heap_[best];
      k = best;
    }
    heap_[k] = last;
    return top;
  }

 private:
  static constexpr std::size_t kArity = 4;
  EventOrder earlier_;
  std::vector<Event> heap_;
};

}  // namespace particle::detail
