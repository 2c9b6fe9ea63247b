#include "diagnosis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>

#include "model.hpp"
#include "tolerance.hpp"

namespace particle::check {

namespace {

bool same(const Candidate& a, const Candidate& b) { return a.t == b.t && a.i == b.i && a.j == b.j; }

// The lowest particle index of a candidate: what a tie broken by index alone goes by.
std::uint32_t lowest(const Candidate& c) { return is_wall(c) ? c.i : std::min(c.i, c.j); }

std::string state_of(const Particles& p, std::size_t i) {
  return fmt::format("({:.8f}, {:.8f}) v ({:.8f}, {:.8f})", p.x[i], p.y[i], p.vx[i], p.vy[i]);
}

// What the model does to particle i in the time unit, from its collision counts alone.
std::string counted_kind(const Particles& model, std::size_t i) {
  if (model.pair_collisions[i] > 0) return "pair collision resolved differently";
  if (model.wall_collisions[i] > 0) return "wall hit resolved differently";
  return "free motion differs";
}

// An alteration and what it would mean.
struct Hypothesis {
  std::string kind, detail;
  Alteration alter;
  std::vector<std::uint32_t> particles;
};

std::vector<std::uint32_t> members(const Candidate& c) {
  return is_wall(c) ? std::vector<std::uint32_t>{c.i} : std::vector<std::uint32_t>{c.i, c.j};
}

// The program skipped the collision `taken` that the model takes for particle i in sub-step k.
Hypothesis missed(const StageStep& stages, int k, const Candidate& taken, std::uint32_t i,
                  const Particles& start, const Particles& printed, const Scene& scene) {
  const Event e = stages.event(k, taken);
  Hypothesis h;
  h.particles = members(taken);
  h.alter = [a = taken, k](int at, const std::vector<Candidate>&,
                           std::vector<Candidate>& accepted) {
    if (at == k) std::erase_if(accepted, [&](const Candidate& c) { return same(c, a); });
  };
  if (e.wall) {
    const double wall_x = start.vx[i] > 0 ? scene.L - scene.r : scene.r;
    const double wall_y = start.vy[i] > 0 ? scene.L - scene.r : scene.r;
    const bool kept = (!e.flips_x || printed.vx[i] == start.vx[i]) &&
                      (!e.flips_y || printed.vy[i] == start.vy[i]);
    const bool parked = (e.flips_x && std::fabs(printed.x[i] - wall_x) <= kPrintRounding) ||
                        (e.flips_y && std::fabs(printed.y[i] - wall_y) <= kPrintRounding);
    h.kind = "wall hit missed";
    h.detail = fmt::format("the model has a {}; the program {}{}", describe(e),
                           kept ? "keeps the velocity" : "misses the hit",
                           parked ? " and parks the particle on the wall" : "");
  } else if (e.overlap) {
    h.kind = "overlapping approaching pair not resolved";
    h.detail =
        fmt::format("the model resolves the {}; the program leaves the pair alone", describe(e));
  } else {
    h.kind = "pair collision missed";
    h.detail = fmt::format("the model has a {}; the program lets the pair pass", describe(e));
  }
  return h;
}

// The program resolved the model's corner hit `taken` (both wall lines at once) as a hit of one
// wall line, `one` (kWallX or kWallY): one component flips, the other keeps its sign.
Hypothesis one_wall(const StageStep& stages, int k, const Candidate& taken, std::uint32_t one) {
  const Candidate instead{taken.t, taken.i, one};
  Hypothesis h;
  h.particles = {taken.i};
  h.alter = [taken, instead, k](int at, const std::vector<Candidate>&,
                                std::vector<Candidate>& accepted) {
    if (at != k) return;
    for (Candidate& c : accepted)
      if (same(c, taken)) c = instead;
  };
  h.kind = "corner hit resolved as a one-wall hit";
  h.detail = fmt::format(
      "the model has a {}: the particle reaches both wall lines at the same time, a corner, and "
      "both components flip; the program flips only {}",
      describe(stages.event(k, taken)), one == kWallX ? "vx" : "vy");
  return h;
}

// The program collided particles i and j at t = 0 of the first sub-step: they overlap there but
// move apart, so the model has no candidate for them (the specification collides an overlapping
// pair only "in the next step", as they meet).
Hypothesis receding(std::uint32_t i, std::uint32_t j, std::size_t n) {
  const Candidate r{0, std::min(i, j), std::max(i, j)};
  Hypothesis h;
  h.particles = {r.i, r.j};
  h.alter = [r, n](int at, const std::vector<Candidate>& ordered,
                   std::vector<Candidate>& accepted) {
    if (at != 0) return;
    std::vector<Candidate> reordered{r};
    reordered.insert(reordered.end(), ordered.begin(), ordered.end());
    std::vector<std::uint8_t> marks(n, 0);
    filter_candidates(reordered, marks, accepted);
  };
  h.kind = "overlapping receding pair resolved";
  h.detail = fmt::format(
      "particles {} and {} overlap at the step's start but move apart, so the model leaves them "
      "alone; the program collides them",
      r.i, r.j);
  return h;
}

// The partners particle i overlaps at `start` while they move apart (the first 4).
std::vector<std::uint32_t> receding_overlaps(const Particles& start, double r, std::uint32_t i) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t j = 0; j < start.size() && out.size() < 4; ++j) {
    if (j == i) continue;
    const double dx = start.x[j] - start.x[i], dy = start.y[j] - start.y[i];
    const double wx = start.vx[j] - start.vx[i], wy = start.vy[j] - start.vy[i];
    if (dx * dx + dy * dy <= 4 * r * r && dx * wx + dy * wy >= 0) out.push_back(j);
  }
  return out;
}

// The program resolved `r`, which the model orders after `taken` (or rejects) in sub-step k.
Hypothesis instead(const StageStep& stages, int k, const Candidate& r, const Candidate* taken,
                   std::vector<std::uint32_t> who, std::size_t n) {
  const Event er = stages.event(k, r);
  Hypothesis h;
  h.particles = std::move(who);
  h.alter = [r, k, n](int at, const std::vector<Candidate>& ordered,
                      std::vector<Candidate>& accepted) {
    if (at != k) return;
    std::vector<Candidate> reordered{r};
    for (const Candidate& c : ordered)
      if (!same(c, r)) reordered.push_back(c);
    std::vector<std::uint8_t> marks(n, 0);
    filter_candidates(reordered, marks, accepted);
  };
  if (taken) {
    const Event ea = stages.event(k, *taken);
    const bool tie = r.t == taken->t;
    // A tie the program breaks by the lower index alone, walls and pairs alike: the 2019
    // authors' rule, which the specification's "the particle collides with the wall" overrides.
    const bool by_index = tie && er.wall != ea.wall && lowest(r) < lowest(*taken);
    h.kind = tie ? fmt::format("{} before {} on a tie", er.wall ? "wall" : "pair",
                               ea.wall ? "wall" : "pair")
                 : "collision order";
    h.detail = fmt::format(
        "the model takes the {} first{}; the program takes the {} instead{}", describe(ea),
        tie ? " (same time: a wall goes before a pair, then the lower indices)" : "", describe(er),
        by_index ? ", as a tie broken by the lower index alone would (the 2019 authors' code)"
                 : "");
  } else {
    h.kind = "collision the model's filter rejects";
    h.detail = fmt::format(
        "the model rejects the {} (a particle of it is taken earlier in the step); the program "
        "resolves it",
        describe(er));
  }
  return h;
}

// The program resolved both `taken` and `r` for particle i in sub-step k.
Hypothesis both(const StageStep& stages, int k, const Candidate& taken, const Candidate& r,
                std::uint32_t i, std::vector<std::uint32_t> who) {
  Hypothesis h;
  h.particles = std::move(who);
  h.alter = [r, k](int at, const std::vector<Candidate>&, std::vector<Candidate>& accepted) {
    if (at == k) accepted.push_back(r);
  };
  h.kind = "two collisions for one particle in a step";
  h.detail = fmt::format(
      "particle {} takes two collisions in one step: the {} and the {}; the model takes only the "
      "first",
      i, describe(stages.event(k, taken)), describe(stages.event(k, r)));
  return h;
}

// Every single alteration of the model's step that could explain particle i: per sub-step, the
// collision it took missed, and each of up to 4 others instead of it or beside it.
std::vector<Hypothesis> hypotheses(const StageStep& stages, const std::vector<SubStep>& record,
                                   std::uint32_t i, const Particles& start,
                                   const Particles& printed, const Scene& scene) {
  std::vector<Hypothesis> out;
  for (std::uint32_t j : receding_overlaps(start, scene.r, i))
    out.push_back(receding(i, j, start.size()));
  for (int k = 0; k < static_cast<int>(record.size()); ++k) {
    const SubStep& sub = record[static_cast<std::size_t>(k)];
    const Candidate* taken = nullptr;
    for (const Candidate& c : sub.accepted)
      if (involves(c, i)) taken = &c;
    std::vector<Candidate> rejected;
    for (const Candidate& c : sub.ordered)
      if (involves(c, i) && !(taken && same(c, *taken)) && rejected.size() < 4)
        rejected.push_back(c);
    if (taken) out.push_back(missed(stages, k, *taken, i, start, printed, scene));
    if (taken && taken->j == kWallCorner)
      for (std::uint32_t one : {kWallX, kWallY}) out.push_back(one_wall(stages, k, *taken, one));
    for (const Candidate& r : rejected) {
      // Where i took nothing, what kept r out is its partner's collision: named with it.
      const Candidate* displaced =
          taken ? taken : (is_wall(r) ? nullptr : collision_of(sub.accepted, r.i == i ? r.j : r.i));
      std::vector<std::uint32_t> who = members(r);
      if (displaced)
        for (std::uint32_t m : members(*displaced))
          if (std::find(who.begin(), who.end(), m) == who.end()) who.push_back(m);
      out.push_back(instead(stages, k, r, displaced, who, start.size()));
      if (taken) out.push_back(both(stages, k, *taken, r, i, who));
    }
  }
  return out;
}

// A program whose order of collisions is wrong in every sub-step, not at one: tried when no single
// alteration explains a particle, as at K > 1, where such a program breaks its rule in several
// sub-steps of a time unit.
struct OrderRule {
  const char* rule;
  bool (*before)(const Candidate& a, const Candidate& b);  // stable-sorted by
};

constexpr OrderRule kOrderRules[] = {
    {"every pair before any wall hit",
     [](const Candidate& a, const Candidate& b) { return !is_wall(a) && is_wall(b); }},
};

// The step as a program following each rule in every sub-step runs it: once per time unit, shared
// by all its violating particles.
struct OrderRun {
  const OrderRule* rule;
  Particles state;
  std::vector<SubStep> record;
};

std::vector<OrderRun> order_runs(const StageStep& stages, std::size_t n) {
  std::vector<OrderRun> runs;
  for (const OrderRule& rule : kOrderRules) {
    const auto alter = [&rule, n](int, const std::vector<Candidate>& ordered,
                                  std::vector<Candidate>& accepted) {
      std::vector<Candidate> reordered = ordered;
      std::stable_sort(reordered.begin(), reordered.end(), rule.before);
      std::vector<std::uint8_t> taken(n, 0);
      filter_candidates(reordered, taken, accepted);
    };
    OrderRun run{&rule, {}, {}};
    run.state = stages.run(alter, &run.record);
    runs.push_back(std::move(run));
  }
  return runs;
}

// Particle i's violation when a program following one of the rules gives its printed values:
// named at the first sub-step where its collision differs from the model's.
std::optional<Hypothesis> broken_order(const StageStep& stages, const std::vector<SubStep>& model,
                                       const std::vector<OrderRun>& runs, std::uint32_t i,
                                       const Particles& start, const Particles& printed,
                                       const Tolerance& tolerance) {
  for (const OrderRun& run : runs) {
    if (difference(run.state, printed, i) > tolerance.of(start, run.state, i)) continue;
    const std::vector<SubStep>& altered = run.record;
    const auto partner = [](const Candidate& c, std::uint32_t p) {
      return is_wall(c) ? p : (c.i == p ? c.j : c.i);
    };
    // Named where the rule first acts: the first sub-step whose collisions differ, by the one
    // the program takes there instead (particle i's where it has one) and the model's it
    // displaces.
    for (int k = 0; k < static_cast<int>(model.size()); ++k) {
      const Candidate* b = nullptr;
      for (const Candidate& c : altered[k].accepted) {
        const bool modelled = std::any_of(model[k].accepted.begin(), model[k].accepted.end(),
                                          [&](const Candidate& m) { return same(m, c); });
        if (!modelled && (!b || (involves(c, i) && !involves(*b, i)))) b = &c;
      }
      if (!b) continue;
      const Candidate* a = collision_of(model[k].accepted, b->i);
      if (!a) a = collision_of(model[k].accepted, partner(*b, b->i));
      if (!a) continue;
      Hypothesis h;
      h.kind = "collision order";
      h.detail = fmt::format(
          "the model takes the {} first; the program takes the {} instead "
          "({}, in every sub-step)",
          describe(stages.event(k, *a)), describe(stages.event(k, *b)), run.rule->rule);
      for (const Candidate* c : {a, b})
        for (std::uint32_t m : {c->i, partner(*c, c->i)})
          if (std::find(h.particles.begin(), h.particles.end(), m) == h.particles.end())
            h.particles.push_back(m);
      return h;
    }
  }
  return std::nullopt;
}

}  // namespace

std::vector<Violation> diagnose(const Scene& scene, const StepRules& rules, const StepStates& s,
                                const std::vector<std::uint32_t>& particles, std::size_t detailed,
                                bool orders) {
  std::vector<Violation> out;
  const Tolerance tolerance(scene, s.start, s.exact_start, rules.wall_stop);
  const StageStep stages(scene, s.start, rules);
  std::vector<SubStep> record;
  if (detailed > 0 || orders) stages.run({}, &record);
  std::optional<std::vector<OrderRun>> runs;  // run when a particle first needs them
  std::set<std::uint32_t> covered;
  for (std::size_t q = 0; q < particles.size(); ++q) {
    const std::uint32_t i = particles[q];
    if (covered.count(i)) continue;
    Violation v;
    v.step = s.step;
    v.particles = {i};
    v.difference = difference(s.model, s.printed, i);
    v.kind = counted_kind(s.model, i);
    v.detail = fmt::format("the model gives {}; the program prints {}", state_of(s.model, i),
                           state_of(s.printed, i));
    std::optional<Hypothesis> found;
    if (q < detailed)
      for (Hypothesis& h : hypotheses(stages, record, i, s.start, s.printed, scene)) {
        const Particles altered = stages.run(h.alter);
        if (std::all_of(h.particles.begin(), h.particles.end(), [&](auto p) {
              return difference(altered, s.printed, p) <= tolerance.of(s.start, altered, p);
            })) {
          found = std::move(h);
          break;
        }
      }
    if (!found && (q < detailed || orders)) {
      if (!runs) runs = order_runs(stages, s.start.size());
      found = broken_order(stages, record, *runs, i, s.start, s.printed, tolerance);
    }
    if (found) {
      v.kind = found->kind;
      v.detail = found->detail;
      v.particles = found->particles;
      std::sort(v.particles.begin(), v.particles.end());
      for (std::uint32_t p : found->particles) {
        covered.insert(p);
        v.difference = std::max(v.difference, difference(s.model, s.printed, p));
      }
    }
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace particle::check
