#include "judge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "diagnosis.hpp"
#include "particle/simulation.hpp"
#include "step_check.hpp"
#include "tolerance.hpp"

namespace particle::check {

namespace {

// Violating particles per time unit whose kind is worked out through the stages; the rest are
// counted by what the model does to them.
constexpr std::size_t kDetailedPerStep = 8;
// Time units with violations that get that much work; later ones get the counted kind only.
constexpr int kDetailedSteps = 20;
// Pair tests that the wrong-order test of the other time units with violations may spend, about
// N^2 K each (two runs of the stages on all pairs): S = 1000 time units of N = 1000 at K = 1, 21
// of N = 10,000; a few seconds in all.
constexpr double kOrderPairTests = 0x1p31;
// A time unit that rounding explains, or that breaks the model, may change a particle's pair and
// wall counts by up to K each.
constexpr std::uint64_t kCountSlack = 2;

// Whether a printed field is `expected`'s text: the same characters, or zero with either sign
// (C's %.8f prints -0.0 and -1e-9 as "-0.00000000": the same number as "0.00000000").
bool same_field(std::string_view printed, std::string_view expected) {
  if (printed == expected) return true;
  const auto unsigned_part = [](std::string_view t) {
    return t.starts_with('-') ? t.substr(1) : t;
  };
  return unsigned_part(printed) == "0.00000000" && unsigned_part(expected) == "0.00000000";
}

// Whether the printed values are, as text, `%.8f` of `state`'s: psim's own formatter, its four
// values at once (" x y vx vy", as Block::bytes holds them), else field by field.
bool same_text(const Block& block, const Particles& state, std::size_t i) {
  char buffer[kMaxStateValuesChars];
  const char* end = print_state_values(buffer, state.x[i], state.y[i], state.vx[i], state.vy[i]);
  const std::string_view x = block.text[4 * i], vy = block.text[4 * i + 3];
  if (std::string_view(x.data() - 1,
                       static_cast<std::size_t>(vy.data() + vy.size() - x.data() + 1)) ==
      std::string_view(buffer, static_cast<std::size_t>(end - buffer)))
    return true;
  const char* at = buffer + 1;
  for (std::size_t f = 0; f < 4; ++f) {
    const char* stop =
        f < 3 ? static_cast<const char*>(std::memchr(at, ' ', static_cast<std::size_t>(end - at)))
              : end;
    if (!same_field(block.text[4 * i + f],
                    std::string_view(at, static_cast<std::size_t>(stop - at))))
      return false;
    at = stop + 1;
  }
  return true;
}

bool finite(const Particles& p, std::size_t i) {
  return std::isfinite(p.x[i]) && std::isfinite(p.y[i]) && std::isfinite(p.vx[i]) &&
         std::isfinite(p.vy[i]);
}

// Whether every value is finite and every centre within [lo, hi] (a NaN fails both comparisons),
// in one pass without branches: almost every state is, and then no particle needs naming. Four
// lanes, as in printed_energy_rounding, so that the compiler takes four particles at once.
bool finite_inside(const Particles& p, double lo, double hi) {
  const std::size_t n = p.size();
  double inside[4] = {1, 1, 1, 1};  // 1 while every particle of the lane is, else 0
  std::size_t i = 0;
  const auto one = [&](std::size_t j) {
    return (p.x[j] >= lo && p.x[j] <= hi && p.y[j] >= lo && p.y[j] <= hi &&
            std::fabs(p.vx[j]) <= DBL_MAX && std::fabs(p.vy[j]) <= DBL_MAX)
               ? 1.0
               : 0.0;
  };
  for (; i + 4 <= n; i += 4)
    for (std::size_t k = 0; k < 4; ++k) inside[k] = std::min(inside[k], one(i + k));
  for (; i < n; ++i) inside[0] = std::min(inside[0], one(i));
  return std::min({inside[0], inside[1], inside[2], inside[3]}) == 1;
}

// The energy of a printed state may differ from the true one by the rounding of its velocities.
// Summed in four lanes: one chain of dependent additions would cost its latency per particle.
double printed_energy_rounding(const Particles& p) {
  const std::size_t n = p.size();
  const auto one = [&](std::size_t j) {
    return (std::fabs(p.vx[j]) + std::fabs(p.vy[j]) + kPrintRounding) * kPrintRounding;
  };
  double lane[4] = {};
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4)
    for (std::size_t k = 0; k < 4; ++k) lane[k] += one(i + k);
  for (; i < n; ++i) lane[0] += one(i);
  return (lane[0] + lane[1]) + (lane[2] + lane[3]);
}

void summarise(Report& r, bool exact) {
  const std::int64_t states =
      static_cast<std::int64_t>(r.print_mode ? r.steps + 1 : (r.final_only ? 1 : 2));
  if (r.violation_count > 0) {
    r.verdict = Verdict::violations;
    const Violation& v = r.violations.front();
    r.summary = fmt::format("{} violation{}; the first at time unit {}, {}: {}", r.violation_count,
                            r.violation_count > 1 ? "s" : "", v.step, particles_phrase(v.particles),
                            v.kind);
  } else if (exact) {
    r.verdict = Verdict::exact;
    r.summary =
        fmt::format("identical to the reference at every printed time unit ({} states)", states);
  } else if (!r.ambiguous.empty()) {
    r.verdict = Verdict::ambiguous;
    r.summary = fmt::format(
        "follows the model except {} time unit{} that the print rounding or a contact "
        "at the step's end can explain",
        r.ambiguous.size(), r.ambiguous.size() > 1 ? "s" : "");
  } else {
    r.verdict = Verdict::consistent;
    r.summary = r.print_mode ? "every time unit follows the model within rounding"
                             : "the final state keeps the invariants";
  }
  if (!r.print_mode && r.verdict != Verdict::exact)
    r.summary +=
        "; perf mode: judged on invariants only (box, finite values, energy, collision "
        "counts), since a chaotic final state cannot be compared; for a judgement, run "
        "the program in print mode on a short scene";
}

}  // namespace

Judge::Judge(const CheckRequest& request, const Scene& scene, const StepRules& rules,
             SharedChunks& shared)
    : scene_(scene),
      rules_(rules),
      k_(request.slow_factor),
      shared_(shared),
      reference_(scene, rules_, shared),
      expected_pairs_(scene.size(), 0),
      expected_walls_(scene.size(), 0),
      slack_(scene.size(), 0),
      energy0_(kinetic_energy(scene.particles)) {
  report_.scene = request.scene;
  report_.output = request.output;
  report_.n = static_cast<std::int64_t>(scene.size());
  report_.steps = scene.steps;
  report_.slow_factor = request.slow_factor;
  report_.print_mode = scene.mode == OutputMode::print;
  report_.reading = std::string(wall_stop_name(rules.wall_stop));
  report_.overlap = std::string(overlap_name(rules.overlap));
}

void Judge::start(const Block& block, bool final_only) {
  report_.final_only = final_only;
  if (final_only)
    report_.notes.push_back(
        "perf mode: the output holds the final state alone, without the step-0 block (a "
        "layout of the 2019 format, as is step 0 then the final state: docs/psim.md)");
  for (std::size_t i = 0; i < scene_.size(); ++i)
    if (!same_text(block, scene_.particles, i)) {
      exact_ = false;
      report_.add({0,
                   {static_cast<std::uint32_t>(i)},
                   "initial state differs from the scene",
                   fmt::format("the scene has ({:.8f}, {:.8f}) v ({:.8f}, {:.8f}); the program "
                               "prints ({:.8f}, {:.8f}) v ({:.8f}, {:.8f})",
                               scene_.particles.x[i], scene_.particles.y[i], scene_.particles.vx[i],
                               scene_.particles.vy[i], block.state.x[i], block.state.y[i],
                               block.state.vx[i], block.state.vy[i]),
                   difference(scene_.particles, block.state, i)});
    }
  invariants(block, block.state);
  if (exact_) ++report_.exact_steps;
}

// `p`: the values the block prints, its own state, or the reference's where the block is
// its text (Block::as_expected). The slack of both checks is the print rounding and more, so the
// reference's values are judged as the text they print would be.
void Judge::invariants(const Block& block, const Particles& p) {
  const auto text = [&](std::size_t k) {
    if (!block.as_expected) return std::string(block.text[k]);
    const std::size_t i = k / 4;
    const double values[] = {p.x[i], p.y[i], p.vx[i], p.vy[i]};
    char buffer[kMaxFixed8Chars];
    return std::string(buffer, print_fixed8(buffer, values[k % 4]));
  };
  const double slack = kPrintRounding + kArithmetic * scene_.L;
  const double lo = scene_.r - slack, hi = scene_.L - scene_.r + slack;
  bool all_finite = true;
  const bool clean = finite_inside(p, lo, hi);
  for (std::size_t i = 0; !clean && i < p.size(); ++i) {
    const auto id = static_cast<std::uint32_t>(i);
    if (!finite(p, i)) {
      all_finite = false;
      report_.add({block.time,
                   {id},
                   "not finite",
                   fmt::format("the program prints ({}, {}) v ({}, {})", text(4 * i),
                               text(4 * i + 1), text(4 * i + 2), text(4 * i + 3)),
                   INFINITY});
      continue;
    }
    for (const double c : {p.x[i], p.y[i]})
      if (c < lo || c > hi)
        report_.add({block.time,
                     {id},
                     "outside the box",
                     fmt::format("position ({:.8f}, {:.8f}) is outside [r, L-r] = [{}, {}]", p.x[i],
                                 p.y[i], scene_.r, scene_.L - scene_.r),
                     std::max(lo - c, c - hi)});
  }
  if (!all_finite) {
    if (usable_)
      report_.notes.push_back(fmt::format(
          "time units after {} are not checked against the model: the printed state is not "
          "finite",
          block.time));
    usable_ = false;
    return;
  }
  if (energy_reported_) return;
  std::uint64_t pairs = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    pairs += block.final ? p.pair_collisions[i] : expected_pairs_[i];
  const double energy = kinetic_energy(p);
  const double allowed = printed_energy_rounding(p) + energy0_ * 0x1p-46 * (1 + pairs);
  if (std::fabs(energy - energy0_) > allowed) {
    energy_reported_ = true;
    report_.add({block.time,
                 {},
                 "energy not conserved",
                 fmt::format("kinetic energy {:.10g} against {:.10g} at time 0 (relative change "
                             "{:.3g}; rounding allows {:.3g})",
                             energy, energy0_, (energy - energy0_) / energy0_, allowed / energy0_),
                 std::fabs(energy - energy0_)});
  }
}

void Judge::count(const Particles& step) {
  for (std::size_t i = 0; i < step.size(); ++i) {
    expected_pairs_[i] += step.pair_collisions[i];
    expected_walls_[i] += step.wall_collisions[i];
  }
}

const Particles* Judge::expects() {
  if (!report_.print_mode || !exact_) return nullptr;
  if (!ahead_) ahead_ = &reference_.next();
  return ahead_;
}

void Judge::follow(const Block& block) {
  if (!report_.print_mode) return;  // perf mode: the final block alone, judged at once
  followed_reference_ = false;
  if (!exact_) {
    invariants(block, block.state);
    return;
  }
  const Particles& step = ahead_ ? *ahead_ : reference_.next();
  ahead_ = nullptr;
  if (block.as_expected) {  // the reference's text, byte for byte
    invariants(block, step);
    count(step);
    ++report_.exact_steps;
    followed_reference_ = true;
    return;
  }
  invariants(block, block.state);
  exact_ = shared_.prints(reference_.chunk(), reference_.index(), block.time, [&] {
    for (std::size_t i = 0; i < step.size(); ++i)
      if (!same_text(block, step, i)) return false;
    return true;
  });
  if (exact_) {
    count(step);
    ++report_.exact_steps;
    followed_reference_ = true;
    return;
  }
  report_.notes.push_back(
      fmt::format("identical to the reference up to time unit {}; checked step by step from there",
                  block.time - 1));
}

void Judge::judge(const Block& block, const Block& previous) {
  if (!report_.print_mode) {
    if (block.final) judge_perf_final(block);
    return;
  }
  // The first time unit starts from the scene's own values, later ones from the printed state.
  if (!followed_reference_ && usable_) {
    if (previous.time == 0)
      model(block, scene_.particles, true);
    else
      model(block, previous.state, false);
  }
  if (block.final) finish(block);
}

// Perf mode: the reference's final state decides `exact`; otherwise invariants only.
void Judge::judge_perf_final(const Block& block) {
  finish(block);
  const States run = shared_.run(scene_, rules_, scene_.particles, scene_.steps, false);
  const Particles& end = run->back();
  perf_exact_ = report_.violation_count == 0;
  for (std::size_t i = 0; i < scene_.size() && perf_exact_; ++i)
    perf_exact_ = same_text(block, end, i) &&
                  block.state.pair_collisions[i] == end.pair_collisions[i] &&
                  block.state.wall_collisions[i] == end.wall_collisions[i];
}

void Judge::model(const Block& block, const Particles& start, bool exact_start) {
  // One time unit from the printed state (its counts zero: a non-final block's, or the scene's),
  // run once for the readings that give the same state from it.
  const States unit = shared_.run(scene_, rules_, start, 1, false);
  const StepResult result =
      check_step(scene_, rules_, block.time, start, exact_start, block.state, unit->back());
  report_.largest_tolerance = std::max(report_.largest_tolerance, result.largest_tolerance);
  count(result.model);
  for (const std::uint32_t i : result.explained) slack_[i] += kCountSlack * k_;
  if (!result.explained.empty())
    report_.ambiguous.push_back(
        {block.time, result.explained, result.largest_difference, result.detail});
  std::vector<std::uint32_t> violating;
  for (const std::uint32_t i : result.unexplained) {
    slack_[i] += kCountSlack * k_;
    if (finite(block.state, i)) violating.push_back(i);  // not finite: reported already
  }
  if (violating.empty()) {
    if (result.explained.empty()) ++report_.consistent_steps;
    return;
  }
  const bool detailed = detailed_steps_++ < kDetailedSteps;
  // A wrong collision order is named wherever it is the cause, as long as the budget lasts.
  const double order_cost = static_cast<double>(k_) * static_cast<double>(scene_.size()) *
                            static_cast<double>(scene_.size());
  const bool orders = detailed || order_pair_tests_ + order_cost <= kOrderPairTests;
  if (!detailed && orders) order_pair_tests_ += order_cost;
  const StepStates states{block.time, start, exact_start, block.state, result.model};
  for (Violation& v :
       diagnose(scene_, rules_, states, violating, detailed ? kDetailedPerStep : 0, orders))
    report_.add(std::move(v));
}

void Judge::finish(const Block& last) {
  const Particles& p = last.state;
  // In perf mode no steps were counted: run_check compares the counts with the reference's run.
  if (exact_ && report_.print_mode) {
    for (std::size_t i = 0; i < p.size() && exact_; ++i)
      exact_ =
          p.pair_collisions[i] == expected_pairs_[i] && p.wall_collisions[i] == expected_walls_[i];
    if (!exact_) report_.notes.push_back("the final collision counts differ from the reference");
  }
  if (!report_.print_mode) {
    // Perf mode: the final state is the only one after step 0, so its invariants are checked
    // here; the counts only for what any run satisfies.
    invariants(last, last.state);
    std::uint64_t pairs = 0;
    const std::uint64_t most = static_cast<std::uint64_t>(scene_.steps) * k_;
    for (std::size_t i = 0; i < p.size(); ++i) {
      pairs += p.pair_collisions[i];
      if (p.pair_collisions[i] + p.wall_collisions[i] > most)
        report_.add({last.time,
                     {static_cast<std::uint32_t>(i)},
                     "collision counts",
                     fmt::format("{} pair and {} wall collisions in {} sub-steps: at most one "
                                 "collision per sub-step",
                                 p.pair_collisions[i], p.wall_collisions[i], most),
                     0});
    }
    if (pairs % 2 != 0)
      report_.add({last.time,
                   {},
                   "collision counts",
                   fmt::format("the pair counts sum to {}, an odd number: each pair collision "
                               "counts on both particles",
                               pairs),
                   0});
    return;
  }
  if (!usable_) return;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto off = [](std::uint64_t a, std::uint64_t b) { return a > b ? a - b : b - a; };
    const std::uint64_t counts_off = off(p.pair_collisions[i], expected_pairs_[i]) +
                                     off(p.wall_collisions[i], expected_walls_[i]);
    if (counts_off <= slack_[i]) continue;
    report_.add({last.time,
                 {static_cast<std::uint32_t>(i)},
                 "collision counts",
                 fmt::format("the program counts {} pair and {} wall collisions; its printed "
                             "steps show {} and {}",
                             p.pair_collisions[i], p.wall_collisions[i], expected_pairs_[i],
                             expected_walls_[i]),
                 static_cast<double>(counts_off)});
  }
}

void Judge::end(bool final_repeated) {
  report_.final_repeated = final_repeated;
  if (final_repeated)
    report_.notes.push_back(
        "print mode: the output prints its last time unit twice, after its step and then as "
        "the final state with its counts, the same values (a layout of the 2019 format, as is "
        "printing it once with its counts: docs/psim.md)");
  summarise(report_, report_.print_mode ? report_.violation_count == 0 && exact_ : perf_exact_);
  finished_ = true;
}

void Judge::malformed(const MalformedOutput& e) {
  report_.verdict = Verdict::malformed;
  report_.malformed = e.what();
  report_.malformed_line = e.line();
  report_.summary = fmt::format("line {}: the output does not have the 2019 format", e.line());
  finished_ = true;
}

Standing Judge::standing() const {
  Verdict verdict = report_.verdict;
  if (!finished_)
    verdict = report_.violation_count > 0 ? Verdict::violations
              : exact_                    ? Verdict::exact
              : report_.ambiguous.empty() ? Verdict::consistent
                                          : Verdict::ambiguous;
  return {static_cast<int>(verdict), report_.violation_count, report_.ambiguous.size()};
}

}  // namespace particle::check
