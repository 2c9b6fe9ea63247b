// The event engine's loop: see event/simulation.hpp for the design.
#include "event/simulation.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "contact.hpp"
#include "particle/io.hpp"
#include "step/pipeline.hpp"

namespace particle::detail {

namespace {

// The largest velocity component, per sub-step: within sqrt(2n) of the speed bound
// sqrt(sum v^2), close enough for the crowding guard's scale, and it cannot overflow.
double largest_component(const World& w) {
  double most = 0;
  for (std::uint32_t i = 0; i < w.n; ++i)
    most = std::max({most, std::fabs(w.ux[i]), std::fabs(w.uy[i])});
  return most;
}

// EventSimulation::unit_budget_; at most 2^64 - 1 (a scene too big for it never reaches it).
std::uint64_t unit_budget(const World& w, int slow_factor) {
  double energy = 0;  // twice the kinetic energy, per sub-step's displacement squared
  for (std::uint32_t i = 0; i < w.n; ++i) energy += w.ux[i] * w.ux[i] + w.uy[i] * w.uy[i];
  const double crossings = std::sqrt(energy) * slow_factor / (w.hi - w.lo);
  const double budget = 0x1p12 * (static_cast<double>(w.n) + 4) * (1 + std::min(crossings, 4.0));
  return budget < 0x1p63 ? static_cast<std::uint64_t>(budget) : UINT64_MAX;
}

}  // namespace

EventSimulation::EventSimulation(const World& w, int slow_factor)
    : w_(w),
      slow_factor_(slow_factor),
      id_(w.n),
      body_(w.n),
      tally_(w.n),
      kept_(w.n),
      grid_(w.L, w.s, w.n),
      queue_(EventOrder{id_.data()}, static_cast<std::uint32_t>(w.n)),
      // At one instant a disk touches at most 6 others and 2 walls, and each contact may come
      // with a stale prediction: far fewer events than this, which a jam (two disks pressed
      // between walls L = 4r apart, fuzz_scene's find) passes within microseconds.
      most_at_once_(64 * static_cast<std::uint64_t>(w.n) + 1024),
      crowd_width_(0x1p-30 * (w.hi - w.lo) / (largest_component(w) * slow_factor)),
      unit_budget_(unit_budget(w, slow_factor)) {
  // Spatial order: a prediction reads the state of ~9 neighbours; stored along the cells'
  // Z-order curve they share cache lines and pages instead of costing a miss each. Stable, so the
  // order is a function of the input alone.
  std::vector<std::uint64_t> key(w.n);
  for (std::uint32_t i = 0; i < w.n; ++i) {
    id_[i] = i;
    key[i] = grid_.spatial_key(w.x[i], w.y[i]);
  }
  std::stable_sort(id_.begin(), id_.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  for (std::uint32_t k = 0; k < w.n; ++k) {
    const std::uint32_t i = id_[k];
    // u * K is exact: K is a power of two.
    body_[k] = {w.x[i], w.y[i], w.ux[i] * slow_factor, w.uy[i] * slow_factor};
    tally_[k] = {0, w.pair_collisions[i], w.wall_collisions[i], w.wall_impulse[i]};
    grid_.insert(k, own(k).cell, w.x[i], w.y[i]);
  }
  for (std::uint32_t k = 0; k < w.n; ++k) queue_.add(k, predict(k, 0));
  queue_.start();
}

void EventSimulation::turn(Body& b, Place p, double vx, double vy, double t) const {
  b = {p.x - vx * (t - epoch_), p.y - vy * (t - epoch_), vx, vy};
}

void EventSimulation::rebase(double t) {
  for (Body& b : body_) b = {x_at(b, t), y_at(b, t), b.vx, b.vy};
  epoch_ = t;
}

Event EventSimulation::predict(std::uint32_t i, double now) {
  const Body& b = body_[i];
  const double x = x_at(b, now), y = y_at(b, now);
  Event best{kNever, i, kNobody, 0};
  const double tx = wall_axis_time(x, b.vx, w_.lo, w_.hi);
  const double ty = wall_axis_time(y, b.vy, w_.lo, w_.hi);
  if (std::min(tx, ty) < kNever) best = {now + std::min(tx, ty), i, wall_kind(tx, ty), 0};
  const std::uint32_t count = grid_.neighbours(i, own(i).cell, near_);
  return add_crossing(i, x, y, earliest_contact(i, x, y, count, now, best), now);
}

Event EventSimulation::predict_after_crossing(std::uint32_t i, std::uint32_t code, double now) {
  const Body& b = body_[i];
  const double x = x_at(b, now), y = y_at(b, now);
  const Kept& k = kept_[i];
  const Event kept{k.t, i, k.other, k.other_count};
  const std::uint32_t count = grid_.new_neighbours(i, own(i).cell, code, near_);
  return add_crossing(i, x, y, earliest_contact(i, x, y, count, now, kept), now);
}

Event EventSimulation::earliest_contact(std::uint32_t i, double x, double y, std::uint32_t count,
                                        double now, Event best) {
  const Body& b = body_[i];
  const std::uint32_t last = own(i).last_partner;
  bool found = false;
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::uint32_t j = near_[k];
    // The pair that has just collided, with no event of either since, recedes for ever.
    if (j == last && own(j).last_partner == i) [[unlikely]] {
      --counters_.pair_tests;
      continue;
    }
    const Body& o = body_[j];
    const PairTerms p =
        pair_terms(x_at(o, now) - x, y_at(o, now) - y, o.vx - b.vx, o.vy - b.vy, w_.s2);
    if (p.c < 0) [[unlikely]] {
      ++counters_.overlaps;
      max_overlap_ = std::max(max_overlap_, 1 - std::sqrt(p.c + w_.s2) / w_.s);
    }
    const double t = now + contact_time(p);
    // Selects, not branches, as in contact_time; equal finite times take the total order.
    const bool tie = (t == best.t) & (t < kNever);
    const bool earlier = (t < best.t) | (tie && queue_.order().tie(Event{t, i, j, 0}, best));
    best.t = earlier ? t : best.t;
    best.other = earlier ? j : best.other;
    found |= earlier;
  }
  counters_.pair_tests += count;
  // The partner's event count, read once for the winner instead of for every neighbour.
  if (found) best.other_count = own(best.other).count;
  return best;
}

Event EventSimulation::add_crossing(std::uint32_t i, double x, double y, Event best, double now) {
  const Body& b = body_[i];
  double tc;
  std::uint32_t code;
  grid_.crossing_time(own(i).cell, x, y, b.vx, b.vy, tc, code);
  if (tc < kNever) {
    const Event crossing{now + tc, i, code, 0};
    if (queue_.order()(crossing, best)) {
      kept_[i] = {best.t, best.other, best.other_count};
      best = crossing;
    }
  }
  if (best.t < kNever) ++counters_.candidates;
  return best;
}

void EventSimulation::collide_wall(const Event& e) {
  Body& b = body_[e.owner];
  Own& o = own(e.owner);
  const Place p = place_at(b, e.t);
  double vx = b.vx, vy = b.vy;
  // Kept per particle in the World's unit, per sub-step (/ K, exact), as the discrete engines do.
  Tally& tally = tally_[e.owner];
  tally.wall_impulse += bounce_off_wall(e.other, vx, vy) / slow_factor_;
  ++tally.wall_collisions;
  --tally.pair_offset;  // count goes up for a wall
  turn(b, p, vx, vy, e.t);
  count_event(e.owner);
  o.last_partner = kNobody;
  ++counters_.wall_collisions;
  queue_.set(e.owner, predict(e.owner, e.t));
}

void EventSimulation::collide_pair(const Event& e) {
  const std::uint32_t i = e.owner, j = e.other;
  queue_.prepare_removal(j);
  Body& a = body_[i];
  Body& b = body_[j];
  const Place pa = place_at(a, e.t), pb = place_at(b, e.t);
  double avx = a.vx, avy = a.vy, bvx = b.vx, bvy = b.vy;
  exchange_along_normal(pb.x - pa.x, pb.y - pa.y, avx, avy, bvx, bvy);
  turn(a, pa, avx, avy, e.t);
  turn(b, pb, bvx, bvy, e.t);
  for (const auto& [k, partner] : {std::pair{i, j}, std::pair{j, i}}) {
    count_event(k);
    own(k).last_partner = partner;
  }
  ++counters_.pair_collisions;
  // Both predictions before either is filed, so that the queue's cache misses for the first
  // overlap the second prediction (the queue is not part of a prediction).
  const Event next_i = predict(i, e.t);
  queue_.prepare(next_i);
  const Event next_j = predict(j, e.t);
  queue_.prepare(next_j);
  queue_.set(i, next_i);
  queue_.set(j, next_j);
}

void EventSimulation::crowded(const Event& e) {
  if (crowded_ == most_at_once_ + 1) crowd_.clear();
  for (const std::uint32_t k : {e.owner, e.is_pair() ? e.other : e.owner})
    if (std::find(crowd_.begin(), crowd_.end(), id_[k]) == crowd_.end()) crowd_.push_back(id_[k]);
  // A few more events, so that every particle of a crowd of several is named.
  if (crowded_ > most_at_once_ + 64) jammed(e.t);
}

void EventSimulation::jammed(double t) const {
  std::vector<std::uint32_t> who = crowd_;
  std::sort(who.begin(), who.end());
  std::string names;
  for (std::size_t k = 0; k < who.size() && k < 8; ++k)
    names += (k == 0 ? "" : k + 1 == who.size() ? " and " : ", ") + std::to_string(who[k]);
  if (who.size() > 8) names += " and " + std::to_string(who.size() - 8) + " more";
  throw InputError(fmt::format(
      "engine event: {} events within {:.3g} time units, up to time {:.17g}, of particle{} {}: "
      "their "
      "collisions come ever closer together and never pass that time (disks pressed together or "
      "against a wall, overlapping or with no gap between their collisions), which an "
      "event-driven simulation cannot step past; a discrete engine (brute, cells, ...) runs "
      "this scene",
      most_at_once_ + 64, std::max(crowd_width_, t * 0x1p-44), t, who.size() == 1 ? "" : "s",
      names));
}

void EventSimulation::too_busy(double horizon) const {
  throw InputError(fmt::format(
      "engine event: more than {} events in time unit {:.0f}, by time {:.17g}: over 4096 per "
      "particle and box crossing (up to 4 crossings), more than a gas needs (4 r N / L), so "
      "disks pressed together or against a wall (overlapping or densely packed) collide without "
      "end, which an event-driven simulation cannot step past; a discrete engine (brute, cells, "
      "...) runs this scene",
      unit_budget_, horizon, now_));
}

bool EventSimulation::run_until(double horizon, const std::atomic<bool>* stop) {
  std::uint64_t events = 0;
  for (;;) {  // checks `stop` also where no event comes for many time units
    if (stop_requested(stop)) return false;
    if (queue_.empty() || queue_.top().t > horizon) break;
    if (++events > unit_budget_) [[unlikely]]
      too_busy(horizon);
    const Event e = queue_.top();
    if (e.t > window_end_) {
      window_end_ = e.t + std::max(crowd_width_, e.t * 0x1p-44);
      crowded_ = 0;
    } else if (++crowded_ > most_at_once_) [[unlikely]] {
      crowded(e);
    }
    now_ = e.t;
    if (e.is_pair()) {
      if (e.other_count != own(e.other).count) {  // the partner changed: predict afresh
        ++stale_;
        queue_.set(e.owner, predict(e.owner, e.t));
      } else {
        collide_pair(e);
      }
    } else if (e.is_wall()) {
      collide_wall(e);
    } else {
      grid_.cross(e.owner, own(e.owner).cell, e.other);
      queue_.set(e.owner, predict_after_crossing(e.owner, e.other, e.t));
    }
  }
  now_ = horizon;
  rebase(horizon);
  return true;
}

double EventSimulation::wall_impulse() const {
  double sum = 0;
  for (const Tally& t : tally_) sum += t.wall_impulse;
  return sum * slow_factor_;
}

void EventSimulation::write_state(double at) const {
  for (std::uint32_t k = 0; k < w_.n; ++k) {
    const Body& b = body_[k];
    const Tally& tally = tally_[k];
    const std::uint32_t i = id_[k];
    const Place p = place_at(b, at);
    w_.x[i] = p.x;
    w_.y[i] = p.y;
    w_.ux[i] = b.vx / slow_factor_;
    w_.uy[i] = b.vy / slow_factor_;
    w_.pair_collisions[i] = tally.pair_offset + tally.count_high + queue_.payload(k).count;
    w_.wall_collisions[i] = tally.wall_collisions;
    w_.wall_impulse[i] = tally.wall_impulse;
  }
}

RunReport run_event(const World& w, const RunOptions& options, const PipelineParams& params) {
  RunReport report;
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;
  EventSimulation sim(w, options.slow_factor);
  for (std::int64_t step = 1; step <= params.steps; ++step) {
    if (!sim.run_until(static_cast<double>(step), params.stop)) {
      report.interrupted = true;
      break;
    }
    if (params.on_time_unit && step < params.steps) {
      watch.lap(unused_s);
      sim.write_state(static_cast<double>(step));
      params.on_time_unit(step);
      watch.lap(output_s);  // printing is not simulation: kept out of wall_s
    }
  }
  report.time_reached = sim.now();
  sim.write_state(sim.now());
  total.lap(report.wall_s);
  report.wall_s -= output_s;
  report.engine = "event";
  report.threads = 1;
  report.cpus = {sched_getcpu()};
  report.counters = sim.counters();
  report.physics.max_overlap = sim.max_overlap();
  return report;
}

}  // namespace particle::detail
