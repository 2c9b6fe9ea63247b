#include "check.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <string_view>

#include "diagnosis.hpp"
#include "model.hpp"
#include "option_values.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/output_path.hpp"
#include "particle/output_text.hpp"
#include "particle/simulation.hpp"
#include "step_check.hpp"
#include "tolerance.hpp"
#include "usage_error.hpp"

namespace particle::check {

namespace {

// Violating particles per time unit whose kind is worked out through the stages; the rest are
// counted by what the model does to them.
constexpr std::size_t kDetailedPerStep = 8;
// Time units with violations that get that much work; later ones get the counted kind only.
constexpr int kDetailedSteps = 20;
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

// Whether the printed values are, as text, `%.8f` of `state`'s: the four at once where the
// program separates them by single spaces as psim does, else one by one.
bool same_text(const Block& block, const Particles& state, std::size_t i) {
  char buffer[kMaxStateValuesChars];
  const std::string_view first = block.text[4 * i], last = block.text[4 * i + 3];
  const char* out = print_state_values(buffer, state.x[i], state.y[i], state.vx[i], state.vy[i]);
  if (std::string_view(first.data() - 1, last.data() + last.size() - first.data() + 1) ==
      std::string_view(buffer, static_cast<std::size_t>(out - buffer)))
    return true;
  const double values[] = {state.x[i], state.y[i], state.vx[i], state.vy[i]};
  for (int f = 0; f < 4; ++f) {
    const char* end = print_fixed8(buffer, values[f]);
    if (!same_field(block.text[4 * i + f],
                    std::string_view(buffer, static_cast<std::size_t>(end - buffer))))
      return false;
  }
  return true;
}

bool finite(const Particles& p, std::size_t i) {
  return std::isfinite(p.x[i]) && std::isfinite(p.y[i]) && std::isfinite(p.vx[i]) &&
         std::isfinite(p.vy[i]);
}

// The energy of a printed state may differ from the true one by the rounding of its velocities.
double printed_energy_rounding(const Particles& p) {
  double sum = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    sum += (std::fabs(p.vx[i]) + std::fabs(p.vy[i]) + kPrintRounding) * kPrintRounding;
  return sum;
}

class Checker {
 public:
  Checker(const Scene& scene, const StepRules& rules, Report& report)
      : scene_(scene),
        rules_(rules),
        k_(rules.slow_factor),
        report_(report),
        reference_(scene.particles),
        expected_pairs_(scene.size(), 0),
        expected_walls_(scene.size(), 0),
        slack_(scene.size(), 0),
        energy0_(kinetic_energy(scene.particles)) {}

  void first(const Block& block);
  void next(const Block& block, const Block& previous);
  void finish(const Block& last);
  bool exact() const { return exact_; }

 private:
  void invariants(const Block& block);
  void model(const Block& block, const Particles& start, bool exact_start);
  void count(const Particles& step_counts);

  const Scene& scene_;
  StepRules rules_;
  int k_;
  Report& report_;
  // The reference run from the scene while the output matches it (its counts: expected_*).
  Particles reference_;
  bool exact_ = true;
  bool usable_ = true;  // the printed states so far can start the model
  std::vector<std::uint64_t> expected_pairs_, expected_walls_, slack_;
  double energy0_;
  bool energy_reported_ = false;
  int detailed_steps_ = 0;
  std::int64_t steps_with_violations_ = 0;
};

void Checker::first(const Block& block) {
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
  invariants(block);
  if (exact_) ++report_.exact_steps;
}

void Checker::invariants(const Block& block) {
  const Particles& p = block.state;
  const double slack = kPrintRounding + kArithmetic * scene_.L;
  const double lo = scene_.r - slack, hi = scene_.L - scene_.r + slack;
  bool all_finite = true;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto id = static_cast<std::uint32_t>(i);
    if (!finite(p, i)) {
      all_finite = false;
      report_.add({block.time,
                   {id},
                   "not finite",
                   fmt::format("the program prints ({}, {}) v ({}, {})", block.text[4 * i],
                               block.text[4 * i + 1], block.text[4 * i + 2], block.text[4 * i + 3]),
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

void Checker::count(const Particles& step) {
  for (std::size_t i = 0; i < step.size(); ++i) {
    expected_pairs_[i] += step.pair_collisions[i];
    expected_walls_[i] += step.wall_collisions[i];
  }
}

void Checker::next(const Block& block, const Block& previous) {
  invariants(block);
  if (exact_) {
    const Particles step = step_time_unit(scene_, reference_, rules_);
    for (std::size_t i = 0; i < step.size() && exact_; ++i) exact_ = same_text(block, step, i);
    if (exact_) {
      reference_ = step;
      count(step);
      ++report_.exact_steps;
      return;
    }
    report_.notes.push_back(fmt::format(
        "identical to the reference up to time unit {}; checked step by step from there",
        block.time - 1));
  }
  if (!usable_) return;
  // The first time unit starts from the scene's own values, later ones from the printed state.
  if (previous.time == 0)
    model(block, scene_.particles, true);
  else
    model(block, previous.state, false);
}

void Checker::model(const Block& block, const Particles& start, bool exact_start) {
  const StepResult result = check_step(scene_, rules_, block.time, start, exact_start, block.state);
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
  ++steps_with_violations_;
  const bool detailed = detailed_steps_++ < kDetailedSteps;
  const StepStates states{block.time, start, exact_start, block.state, result.model};
  for (Violation& v : diagnose(scene_, rules_, states, violating, detailed ? kDetailedPerStep : 0))
    report_.add(std::move(v));
}

void Checker::finish(const Block& last) {
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
    invariants(last);
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

// The output judged under one reading of the specification.
Report check_reading(const CheckRequest& request, const Scene& scene, WallStop reading) {
  Report report;
  report.scene = request.scene;
  report.output = request.output;
  report.n = static_cast<std::int64_t>(scene.size());
  report.steps = scene.steps;
  report.slow_factor = request.slow_factor;
  report.print_mode = scene.mode == OutputMode::print;
  report.reading = std::string(wall_stop_name(reading));
  const StepRules rules{request.slow_factor, reading};
  Checker checker(scene, rules, report);
  bool exact = false;
  try {
    OutputReader reader(request.output, scene);
    Block previous, block;
    reader.next(previous);
    report.final_only = reader.final_only();
    if (report.final_only)
      report.notes.push_back(
          "perf mode: the output holds the final state alone, without the step-0 block (a "
          "layout of the 2019 format, as is step 0 then the final state: docs/psim.md)");
    checker.first(previous);
    while (reader.next(block)) {
      if (report.print_mode) checker.next(block, previous);
      if (block.final) checker.finish(block);
      if (!report.print_mode) {
        // Perf mode: the reference's final state decides `exact`; otherwise invariants only.
        Scene run = scene;
        RunOptions options;
        options.threads = 1;
        options.slow_factor = request.slow_factor;
        options.wall_stop = reading;
        simulate(run, options);
        exact = report.violation_count == 0;
        for (std::size_t i = 0; i < scene.size() && exact; ++i)
          exact = same_text(block, run.particles, i) &&
                  block.state.pair_collisions[i] == run.particles.pair_collisions[i] &&
                  block.state.wall_collisions[i] == run.particles.wall_collisions[i];
      }
      std::swap(previous, block);
    }
    report.final_repeated = reader.final_repeated();
    if (report.final_repeated)
      report.notes.push_back(
          "print mode: the output prints its last time unit twice, after its step and then as "
          "the final state with its counts, the same values (a layout of the 2019 format, as is "
          "printing it once with its counts: docs/psim.md)");
    if (report.print_mode) exact = report.violation_count == 0 && checker.exact();
  } catch (const MalformedOutput& e) {
    report.verdict = Verdict::malformed;
    report.malformed = e.what();
    report.malformed_line = e.line();
    report.summary = fmt::format("line {}: the output does not have the 2019 format", e.line());
    return report;
  }
  summarise(report, exact);
  return report;
}

// How well a report's output follows its reading: the verdict, then fewer violations, then fewer
// time units that only rounding explains.
auto standing(const Report& r) {
  return std::tuple(static_cast<int>(r.verdict), r.violation_count, r.ambiguous.size());
}

}  // namespace

Report run_check(const CheckRequest& request) {
  std::ifstream in(request.scene, std::ios::binary);
  if (!in)
    throw InputError(fmt::format("{}: cannot open: {}", request.scene, std::strerror(errno)));
  const Scene scene = read_scene(in, request.scene, RandomInit{});
  check_representable(scene, request.slow_factor, request.scene);
  if (request.wall_stop) {
    Report report = check_reading(request, scene, *request.wall_stop);
    report.reading_required = true;
    return report;
  }
  // Every reading the specification allows; the output is judged by the one it follows best,
  // and nothing counts against it that some reading allows.
  Report best = check_reading(request, scene, kWallStops[0]);
  if (best.verdict == Verdict::malformed) return best;  // the format is every reading's
  for (std::size_t k = 1; k < std::size(kWallStops); ++k) {
    Report other = check_reading(request, scene, kWallStops[k]);
    if (standing(other) == standing(best))
      best.reading = "either";  // the output does not tell the readings apart
    else if (standing(other) < standing(best))
      best = std::move(other);
  }
  return best;
}

int check_main(int argc, char** argv) {
  CLI::App app{
      "psim check: whether OUTPUT, another program's output for SCENE (2019 format; OUTPUT - is "
      "stdin), follows the model; exit 0 exact, consistent or ambiguous, 1 violations, 2 "
      "malformed or bad input",
      "psim check"};
  CheckRequest request;
  std::string slow_factor, wall_stop, json;
  app.add_option("SCENE", request.scene, "the scene the program was given (2019 input format)")
      ->type_name("FILE")
      ->required();
  app.add_option("OUTPUT", request.output, "the program's output (- for stdin)")
      ->type_name("FILE")
      ->required();
  app.add_option("--slow-factor", slow_factor,
                 fmt::format("sub-steps per time unit of the run, a power of two from 1 to {}",
                             kMaxSlowFactor))
      ->type_name("K")
      ->default_str("1");
  app.add_option("--wall-stop", wall_stop,
                 "the wall-stop reading the output must follow, per-coordinate or whole-motion "
                 "(default: either; the report names the one it follows)")
      ->type_name("READING");
  app.add_option("--json", json, "also write the full report as JSON to FILE")->type_name("FILE");
  try {
    app.parse(argc, argv);
    if (!slow_factor.empty()) request.slow_factor = lab::slow_factor_option(slow_factor);
    if (app.count("--wall-stop")) request.wall_stop = lab::wall_stop_option(wall_stop);
    if (app.count("--json")) json = lab::path_option("--json", json);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "psim check: %s\n", lab::usage_message(e, "psim check").c_str());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "psim check: %s\n", e.what());
    return 2;
  }
  try {
    // Checked before the output is read, like psim's --metrics: a directory, the scene or the
    // output itself is refused up front.
    std::optional<lab::WholeFile> json_file;
    if (!json.empty()) {
      json_file.emplace(json, "--json");
      for (const std::string& input : {request.scene, request.output})
        if (json_file->target().same_file(output_target(input)))
          throw InputError(fmt::format("--json: {} is {}; name another file", json, input));
    }
    const Report report = run_check(request);
    std::fputs(to_text(report).c_str(), stdout);
    if (json_file) write_json(report, *json_file);
    return exit_status(report.verdict);
  } catch (const std::exception& e) {  // the scene (InputError), its limits, an unwritable --json
    std::fprintf(stderr, "psim check: %s\n", e.what());
    return 2;
  }
}

}  // namespace particle::check
