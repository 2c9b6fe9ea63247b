#pragma once
// The event engine's calendar: one slot per particle, ordered by a calendar queue of time bins.
//
// Each particle owns exactly one prediction, its earliest event (pair, wall or cell crossing;
// infinitely late when it has none). A new prediction replaces the particle's old one in place,
// so the queue holds at most N entries and never a stale one: a collision re-predicts both of its
// particles, which overwrites every prediction it made wrong except those of third particles that
// had predicted a contact with one of them; such a pair event carries the partner's event counter
// and is found out when it surfaces (event/simulation.cpp re-predicts its owner). This is the
// "one event per particle" scheme of DynamO and of Smallenburg's EDMD.
//
// The calendar (Paul, J. Comput. Phys. 221, 2007): time is cut into bins of width w from an
// origin t0; a ring of M bins holds the predictions of the next M bins as unsorted singly linked
// lists, later ones wait in an overflow list. Only the current bin's predictions are sorted, in
// a small 4-ary heap; when it runs empty the next non-empty bin's list is moved into it, and
// every M bins the overflow list is dealt into the ring. A new prediction then costs O(1) (a list
// insert) unless it falls into the current bin, instead of a walk through a heap of N. Bins are
// ordered as their times (the bin of t, floor((t - t0) / w), never decreases with t), so events
// come out in the exact total order below whatever w is; w only sets the speed: about 2 events
// per bin, from the median time to the particles' next events, and chosen afresh where bins turn
// out mostly empty (the event rate fell) or the ring has run empty (a jump to the next event).
//
// Memory is the cost at large N (the engine's working set is about the last-level cache at
// N = 100,000): an entry is 32 bytes with the caller's payload, the lists are singly linked
// (a removal walks its bin's few predictions) and a heap slot and a list link share one field.
// Measured on dense30: 2 events per bin 2-5% faster than 4 and 1, 8 slower still.
//
// Order: the total order (time, kind, lower particle, higher particle, owner) with input indices,
// walls before pairs before cell crossings at equal times (the discrete model's wall-first rule).
// Live predictions never have equal keys, so the run never depends on how ties are broken.
#include <algorithm>
#include <cmath>
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
// (event/simulation.cpp); `id` maps them back to input indices, which break ties.
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

// An empty payload: a queue of events only.
struct NoPayload {};

// Payload: the caller's own per-particle record, kept in the particle's queue entry so that an
// event reads its particle's prediction and record in one cache line (payload()).
template <class Payload = NoPayload>
class EventQueue {
 public:
  // Particles 0 to n - 1, each with no event: give each its first prediction with add(), then
  // start().
  EventQueue(EventOrder earlier, std::uint32_t n)
      : earlier_(earlier), entry_(n), heap_(n), ring_(ring_size(n), kEnd) {}

  void add(std::uint32_t p, const Event& e) { entry_[p].hold(e); }
  void start() { rebuild(); }

  EventOrder order() const { return earlier_; }

  Payload& payload(std::uint32_t p) { return entry_[p].user; }
  const Payload& payload(std::uint32_t p) const { return entry_[p].user; }

  // No particle has an event.
  bool empty() const { return count_ == 0; }

  // The earliest prediction; only when !empty().
  Event top() {
    while (heap_size_ == 0) next_bin();
    return event(heap_[0].p);
  }

  // Starts loading the list head of e's bin, which set() will read and write: called well
  // before set(), the cache miss overlaps other work.
  void prepare(const Event& e) const {
    const std::int64_t b = bin_of(e.t);
    if (b > cur_ && b < base_ + ring_bins()) __builtin_prefetch(&ring_[ring_slot(b)]);
  }

  // The same for the list that set(p, ...) will take p's present prediction from.
  void prepare_removal(std::uint32_t p) const {
    const Entry& x = entry_[p];
    if ((x.place & ~kEnd) == kRingBit) __builtin_prefetch(&ring_[ring_slot(bin_of(x.t))]);
  }

  // Replaces p's prediction by e.
  void set(std::uint32_t p, const Event& e) {
    Entry& x = entry_[p];
    if (x.place < kRingBit && e.t < kNever && bin_of(e.t) <= cur_) {  // stays in the current bin
      const bool later = !earlier_(e, event(p));
      x.hold(e);
      heap_[x.place].t = e.t;
      if (later)
        sift_down(x.place);
      else
        sift_up(x.place);
      return;
    }
    remove(p);
    x.hold(e);
    insert(p);
  }

 private:
  static constexpr double kNever = std::numeric_limits<double>::infinity();
  static constexpr std::int64_t kFar = std::int64_t{1} << 62;  // bins beyond every ring
  // Entry::place: a heap slot (below kRingBit), kRingBit | the next particle of its ring bin's
  // list (kEnd at the end), kInOverflow or kNowhere (no event). Particle indices stay below
  // kEnd (psim's limit is 10^8).
  static constexpr std::uint32_t kRingBit = 0x40000000u, kEnd = kRingBit - 1;
  static constexpr std::uint32_t kInOverflow = 0xFFFFFFFEu, kNowhere = 0xFFFFFFFFu;
  static constexpr std::uint32_t kArity = 4;
  static constexpr double kEventsPerBin = 2;

  // A particle's prediction (its Event without the owner, which is the particle), place and
  // payload, aligned so that an entry never straddles two cache lines (the queue's loads are
  // cache misses).
  static constexpr std::size_t kEntryAlign = 20 + sizeof(Payload) <= 32 ? 32 : 64;
  struct alignas(kEntryAlign) Entry {
    double t = kNever;
    std::uint32_t other = 0, other_count = 0;
    std::uint32_t place = kNowhere;
    Payload user{};
    void hold(const Event& e) {
      t = e.t;
      other = e.other;
      other_count = e.other_count;
    }
  };
  Event event(std::uint32_t p) const {
    const Entry& x = entry_[p];
    return {x.t, p, x.other, x.other_count};
  }
  // The list head of bin b (within the ring's M bins from base_: slot b mod M). A ring entry's bin
  // is a function of its time: t0 and w change only in rebuild(), which files every entry again.
  std::size_t ring_slot(std::int64_t b) const {
    return static_cast<std::size_t>(b) & (ring_.size() - 1);
  }
  std::uint32_t& ring_head(std::int64_t b) { return ring_[ring_slot(b)]; }
  struct Node {  // a heap slot: the time next to the particle, so sifts compare without entry_
    double t;
    std::uint32_t p;
  };

  // A power of two: predictions reach some 8 median times ahead.
  static std::size_t ring_size(std::uint32_t n) {
    std::size_t m = 16;
    while (static_cast<double>(m) < 8 * static_cast<double>(n) / kEventsPerBin) m *= 2;
    return m;
  }
  std::int64_t ring_bins() const { return static_cast<std::int64_t>(ring_.size()); }

  // floor((t - t0) / w): never decreases with t (each rounding is monotonic); t >= t0.
  std::int64_t bin_of(double t) const {
    const double q = (t - t0_) / width_;
    return q < static_cast<double>(kFar) ? static_cast<std::int64_t>(q) : kFar;
  }

  void insert(std::uint32_t p) {
    Entry& x = entry_[p];
    if (!(x.t < kNever)) {
      x.place = kNowhere;
      return;
    }
    ++count_;
    const std::int64_t b = bin_of(x.t);
    if (b <= cur_) {
      heap_[heap_size_] = {x.t, p};
      x.place = heap_size_++;
      sift_up(x.place);
    } else if (b < base_ + ring_bins()) {
      link(ring_head(b), p);
      ++in_ring_;
    } else {
      x.place = kInOverflow;
      overflow_.push_back(p);
    }
  }

  void remove(std::uint32_t p) {
    Entry& x = entry_[p];
    if (x.place == kNowhere) return;
    --count_;
    if ((x.place & ~kEnd) == kRingBit) {
      unlink(ring_head(bin_of(x.t)), p);
      --in_ring_;
    } else if (x.place == kInOverflow) {
      // Left in overflow_: dealing it skips a particle no longer kInOverflow.
    } else {  // the heap: its last node takes the slot
      const std::uint32_t k = x.place;
      const Node last = heap_[--heap_size_];
      if (k < heap_size_) {
        const bool later = before(heap_[k], last);
        place(k, last);
        if (later)
          sift_down(k);
        else
          sift_up(k);
      }
    }
    x.place = kNowhere;
  }

  // The current bin is empty: moves on to the next bin, dealing the overflow into the ring when
  // the ring turns over; starts afresh when the ring is empty or the last turn found the bins
  // mostly empty.
  void next_bin() {
    if (in_ring_ == 0 || bins_seen_ > 8 * (events_seen_ + 1) + ring_bins()) {
      rebuild();
      return;
    }
    ++cur_;
    ++bins_seen_;
    if (cur_ == base_ + ring_bins()) {
      base_ = cur_;
      // A particle may have left the overflow and come back: claim each once, then file.
      std::vector<std::uint32_t> dealt;
      dealt.swap(overflow_);
      std::size_t kept = 0;
      for (const std::uint32_t p : dealt)
        if (entry_[p].place == kInOverflow) {
          entry_[p].place = kNowhere;
          --count_;
          dealt[kept++] = p;
        }
      for (std::size_t k = 0; k < kept; ++k) insert(dealt[k]);
    }
    std::uint32_t& head = ring_head(cur_);
    for (std::uint32_t p = head; p != kEnd;) {
      const std::uint32_t next = entry_[p].place & kEnd;
      --count_;
      --in_ring_;
      insert(p);  // bin cur_: into the heap
      p = next;
      ++events_seen_;
    }
    head = kEnd;
    // The next bins' first predictions, whose entries a list walk would otherwise wait for one
    // after another.
    for (std::int64_t ahead = 1; ahead <= 2; ++ahead)
      if (const std::uint32_t p = ring_head(cur_ + ahead); p != kEnd)
        __builtin_prefetch(&entry_[p]);
  }

  // Chooses t0 and w from the predictions and files every one of them again: t0 the earliest
  // time, w such that about kEventsPerBin of them fall in a bin of the median distance from t0.
  void rebuild() {
    std::vector<double> ahead;
    double t0 = kNever;
    for (const Entry& x : entry_)
      if (x.t < kNever) t0 = std::min(t0, x.t);
    for (const Entry& x : entry_)
      if (x.t < kNever && x.t > t0) ahead.push_back(x.t - t0);
    double width = 1;
    if (!ahead.empty()) {
      std::nth_element(ahead.begin(), ahead.begin() + ahead.size() / 2, ahead.end());
      width = kEventsPerBin * ahead[ahead.size() / 2] / static_cast<double>(ahead.size());
    }
    t0_ = t0 < kNever ? t0 : 0;
    width_ = width > 0 && width < kNever ? width : 1;
    std::fill(ring_.begin(), ring_.end(), kEnd);
    overflow_.clear();
    cur_ = base_ = 0;
    heap_size_ = 0;
    count_ = in_ring_ = 0;
    bins_seen_ = events_seen_ = 0;
    for (std::uint32_t p = 0; p < entry_.size(); ++p) insert(p);
  }

  // A bin's list is singly linked (an entry's 4 bytes of a back link would double its size with
  // the payload): a removal walks the bin's few predictions.
  void link(std::uint32_t& head, std::uint32_t p) {
    entry_[p].place = kRingBit | head;
    head = p;
  }
  void unlink(std::uint32_t& head, std::uint32_t p) {
    const std::uint32_t after = entry_[p].place & kEnd;
    if (head == p) {
      head = after;
      return;
    }
    std::uint32_t q = head;
    while ((entry_[q].place & kEnd) != p) q = entry_[q].place & kEnd;
    entry_[q].place = kRingBit | after;
  }

  bool before(const Node& a, const Node& b) const {
    if (a.t != b.t) [[likely]]
      return a.t < b.t;
    return earlier_.tie(event(a.p), event(b.p));
  }
  void place(std::uint32_t k, const Node& n) {
    heap_[k] = n;
    entry_[n.p].place = k;
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
      if (first >= heap_size_) break;
      std::uint32_t best = first;
      const std::uint32_t end = std::min(first + kArity, heap_size_);
      for (std::uint32_t c = first + 1; c < end; ++c)
        if (before(heap_[c], heap_[best])) best = c;
      if (!before(heap_[best], n)) break;
      place(k, heap_[best]);
      k = best;
    }
    place(k, n);
  }

  EventOrder earlier_;
  std::vector<Entry> entry_;  // per particle
  std::vector<Node> heap_;    // the current bin's predictions, a 4-ary min-heap
  std::uint32_t heap_size_ = 0;
  std::vector<std::uint32_t> ring_;      // first particle of each bin's list, bin b at b mod M
  std::vector<std::uint32_t> overflow_;  // particles beyond the ring, and some that have left
  double t0_ = 0, width_ = 1;            // bin b holds times t with floor((t - t0) / w) = b
  std::int64_t cur_ = 0;                 // the current bin, the heap's
  std::int64_t base_ = 0;                // the ring holds bins base_ .. base_ + M - 1
  std::uint32_t count_ = 0;              // particles with an event
  std::uint32_t in_ring_ = 0;            // of them in the ring
  std::int64_t bins_seen_ = 0, events_seen_ = 0;  // since the last rebuild
};

}  // namespace particle::detail
