// The event engine's calendar queue (event/queue.hpp) against a linear search for the earliest
// prediction under the same total order, through the paths that bins make possible: times
// spread over twelve orders of magnitude (the overflow list, ring turns), exact ties (the order's
// tie break inside a bin), particles without events, a rate that falls a thousandfold (bins
// chosen afresh) and a queue whose every event is far beyond the ring (a jump).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "event/queue.hpp"

namespace particle::detail {
namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

class QueueModel {
 public:
  explicit QueueModel(std::uint32_t n) : id_(n), events_(n) {
    std::iota(id_.rbegin(), id_.rend(), 0u);  // input order reversed: ties go by id, not slot
  }
  EventOrder order() const { return {id_.data()}; }
  std::vector<Event>& events() { return events_; }

  // The earliest event by linear search; nullptr when none is finite.
  const Event* earliest() const {
    const Event* best = nullptr;
    for (const Event& e : events_)
      if (e.t < kNever && (best == nullptr || order()(e, *best))) best = &e;
    return best;
  }

 private:
  std::vector<std::uint32_t> id_;
  std::vector<Event> events_;
};

// A prediction of p from `now` on: a tie (0), a short, long or far time, on a grid of 1/8 (so
// equal times recur), or none; partner a particle or a wall or crossing code.
Event draw(std::mt19937_64& rng, std::uint32_t p, std::uint32_t n, double now, double scale) {
  std::uniform_real_distribution<double> unit(0, 1);
  const double u = unit(rng);
  double dt;
  if (u < 0.05)
    dt = 0;
  else if (u < 0.1)
    dt = kNever;
  else if (u < 0.12)
    dt = scale * 1e6 * unit(rng);
  else if (u < 0.3)
    dt = std::floor(scale * 8 * unit(rng)) / 8;
  else
    dt = -scale * std::log(1 - unit(rng));
  const std::uint32_t codes[] = {kWallX, kCrossXLow, kCrossYHigh};
  const std::uint32_t other =
      unit(rng) < 0.7 ? static_cast<std::uint32_t>(rng() % n) : codes[rng() % 3];
  return {now + dt, p, other == p ? kWallY : other, 0};
}

TEST(EventQueue, PopsInTheTotalOrderOfALinearSearch) {
  constexpr std::uint32_t n = 300;
  std::mt19937_64 rng(7);
  QueueModel model(n);
  EventQueue queue(model.order(), n);
  for (std::uint32_t p = 0; p < n; ++p) {
    model.events()[p] = draw(rng, p, n, 0, 1);
    queue.add(p, model.events()[p]);
  }
  queue.start();
  double now = 0, scale = 1;
  for (int step = 0; step < 200000; ++step) {
    if (step == 100000) scale = 1e-3;  // the rate rises a thousandfold ...
    if (step == 150000) scale = 1e3;   // ... then falls a millionfold
    if (step == 190000)                // every event gone
      for (std::uint32_t p = 0; p < n; ++p) {
        model.events()[p].t = kNever;
        queue.set(p, model.events()[p]);
      }
    const Event* expected = model.earliest();
    ASSERT_EQ(queue.empty(), expected == nullptr) << "step " << step;
    if (expected == nullptr) {  // all events gone: the next ones lie far beyond every ring
      for (std::uint32_t p = 0; p < n; p += 7) {
        model.events()[p] = {now + 1e12 + p, p, kWallX, 0};
        queue.set(p, model.events()[p]);
      }
      continue;
    }
    const Event& got = queue.top();
    ASSERT_EQ(got.owner, expected->owner) << "step " << step;
    ASSERT_EQ(got.t, expected->t) << "step " << step;
    ASSERT_GE(got.t, now);
    now = got.t;
    // As the engine does: the owner gets a new prediction, and so, sometimes, does another.
    const std::uint32_t owner = got.owner;
    model.events()[owner] = draw(rng, owner, n, now, scale);
    queue.set(owner, model.events()[owner]);
    if (rng() % 2 == 0) {
      const std::uint32_t q = static_cast<std::uint32_t>(rng() % n);
      model.events()[q] = draw(rng, q, n, now, scale);
      queue.set(q, model.events()[q]);
    }
  }
}

}  // namespace
}  // namespace particle::detail
