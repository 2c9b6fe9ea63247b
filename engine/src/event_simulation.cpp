// The event engine's loop: see event_simulation.hpp for the design.
#include "event_simulation.hpp"

#include <algorithm>
#include <cmath>

#include "contact.hpp"
#include "narrow_phase.hpp"
#include "pipeline.hpp"

namespace particle::detail {

EventSimulation::EventSimulation(const World& w, int slow_factor)
    : w_(w),
      slow_factor_(slow_factor),
      id_(w.n),
      body_(w.n),
      grid_(w.L, w.s, w.n),
      queue_(EventOrder{id_.data()}, static_cast<std::uint32_t>(w.n)) {
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
    body_[k] = {w.x[i], w.y[i], w.ux[i] * slow_factor, w.uy[i] * slow_factor, 0, 0, kNobody,
                kNever, kNobody, 0};
    grid_.insert(k, w.x[i], w.y[i]);
  }
  for (std::uint32_t k = 0; k < w.n; ++k) queue_.add(k, predict(k, 0));
  queue_.start();
}

void EventSimulation::advance(Body& b, double now) const {
  const double dt = now - b.t;
  // The clamp only catches rounding: a real crossing of a wall line is a wall event first.
  b.x = std::clamp(b.x + b.vx * dt, w_.lo, w_.hi);
  b.y = std::clamp(b.y + b.vy * dt, w_.lo, w_.hi);
  b.t = now;
}

Event EventSimulation::predict(std::uint32_t i, double now) {
  Body& b = body_[i];
  advance(b, now);
  Event best{kNever, i, kNobody, 0};
  const double tx = wall_axis_time(b.x, b.vx, w_.lo, w_.hi);
  const double ty = wall_axis_time(b.y, b.vy, w_.lo, w_.hi);
  if (std::min(tx, ty) < kNever) best = {now + std::min(tx, ty), i, wall_kind(tx, ty), 0};
  grid_.for_each_neighbour(i, [&](std::uint32_t j) { test_pair(i, j, now, best); });
  return keep_and_add_crossing(i, best, now);
}

Event EventSimulation::predict_after_crossing(std::uint32_t i, std::uint32_t code, double now) {
  Body& b = body_[i];
  advance(b, now);
  Event best{b.kept_t, i, b.kept_other, b.kept_other_count};
  grid_.for_each_new_neighbour(i, code, [&](std::uint32_t j) { test_pair(i, j, now, best); });
  return keep_and_add_crossing(i, best, now);
}

void EventSimulation::test_pair(std::uint32_t i, std::uint32_t j, double now, Event& best) {
  const Body& b = body_[i];
  const Body& o = body_[j];
  // The pair that has just collided, with no event of either since, recedes for ever.
  if (b.last_partner == j && o.last_partner == i) return;
  ++counters_.pair_tests;
  const double dt = now - o.t;
  const PairTerms p =
      pair_terms(o.x + o.vx * dt - b.x, o.y + o.vy * dt - b.y, o.vx - b.vx, o.vy - b.vy, w_.s2);
  if (p.c < 0) [[unlikely]] {
    ++counters_.overlaps;
    max_overlap_ = std::max(max_overlap_, 1 - std::sqrt(p.c + w_.s2) / w_.s);
  }
  double t;
  if (!contact_time(p, t)) return;
  const Event pair{now + t, i, j, o.count};
  if (queue_.order()(pair, best)) best = pair;
}

Event EventSimulation::keep_and_add_crossing(std::uint32_t i, Event best, double now) {
  Body& b = body_[i];
  b.kept_t = best.t;
  b.kept_other = best.other;
  b.kept_other_count = best.other_count;
  double tc;
  std::uint32_t code;
  grid_.crossing_time(i, b.x, b.y, b.vx, b.vy, tc, code);
  if (tc < kNever) {
    const Event crossing{now + tc, i, code, 0};
    if (queue_.order()(crossing, best)) best = crossing;
  }
  if (best.t < kNever) ++counters_.candidates;
  return best;
}

void EventSimulation::collide_wall(const Event& e) {
  Body& b = body_[e.owner];
  advance(b, e.t);
  // Kept per particle in the World's unit, per sub-step (/ K, exact), as the discrete engines do.
  w_.wall_impulse[id_[e.owner]] += bounce_off_wall(e.other, b.vx, b.vy) / slow_factor_;
  ++b.count;
  b.last_partner = kNobody;
  ++w_.wall_collisions[id_[e.owner]];
  ++counters_.wall_collisions;
  queue_.set(e.owner, predict(e.owner, e.t));
}

void EventSimulation::collide_pair(const Event& e) {
  const std::uint32_t i = e.owner, j = e.other;
  Body& a = body_[i];
  Body& b = body_[j];
  advance(a, e.t);
  advance(b, e.t);
  exchange_along_normal(b.x - a.x, b.y - a.y, a.vx, a.vy, b.vx, b.vy);
  ++a.count;
  ++b.count;
  a.last_partner = j;
  b.last_partner = i;
  ++w_.pair_collisions[id_[i]];
  ++w_.pair_collisions[id_[j]];
  ++counters_.pair_collisions;
  queue_.set(i, predict(i, e.t));
  queue_.set(j, predict(j, e.t));
}

bool EventSimulation::run_until(double horizon, const std::atomic<bool>* stop) {
  for (;;) {  // checks `stop` also where no event comes for many time units
    if (stop_requested(stop)) return false;
    if (queue_.empty() || queue_.top().t > horizon) break;
    const Event e = queue_.top();
    now_ = e.t;
    if (e.is_pair()) {
      if (e.other_count != body_[e.other].count) {  // the partner changed: predict afresh
        ++stale_;
        queue_.set(e.owner, predict(e.owner, e.t));
      } else {
        collide_pair(e);
      }
    } else if (e.is_wall()) {
      collide_wall(e);
    } else {
      grid_.cross(e.owner, e.other);
      queue_.set(e.owner, predict_after_crossing(e.owner, e.other, e.t));
    }
  }
  now_ = horizon;
  return true;
}

double EventSimulation::wall_impulse() const {
  double sum = 0;
  for (std::size_t i = 0; i < w_.n; ++i) sum += w_.wall_impulse[i];
  return sum * slow_factor_;
}

void EventSimulation::write_state(double at) const {
  for (std::uint32_t k = 0; k < w_.n; ++k) {
    Body b = body_[k];
    advance(b, at);
    const std::uint32_t i = id_[k];
    w_.x[i] = b.x;
    w_.y[i] = b.y;
    w_.ux[i] = b.vx / slow_factor_;
    w_.uy[i] = b.vy / slow_factor_;
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
