#include "check.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <climits>
#include <cstring>
#include <deque>
#include <fstream>
#include <optional>
#include <vector>

#include "judge.hpp"
#include "option_values.hpp"
#include "output_source.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/output_path.hpp"
#include "particle/output_text.hpp"
#include "usage_error.hpp"

namespace particle::check {

namespace {

// A reading in the judging: its judge, and how far it has read.
struct Reading {
  Reading(const CheckRequest& request, const Scene& scene, const StepRules& rules,
          SharedChunks& shared)
      : rules(rules), judge(request, scene, rules, shared) {}
  StepRules rules;
  Judge judge;
  std::uint64_t taken = 0;  // blocks taken in full
  bool followed = false;    // the next block's follow() is done (set aside between the two)
};

// Sets aside every reading of `active` whose standing is worse than the best active one's, or
// than `bound` (the best final standing so far): it can no longer be the best.
void set_aside(std::vector<Reading*>& active, const std::optional<Standing>& bound) {
  Standing best = bound.value_or(Standing{INT_MAX, 0, 0});
  for (const Reading* r : active) best = std::min(best, r->judge.standing());
  std::erase_if(active, [&](const Reading* r) { return r->judge.standing() > best; });
}

// The text of the next block (time unit `time`) where every active reading expects it to print
// one state (Judge::expects): the readings that follow the reference and share its run. Empty
// where they do not, and where a reading taken up again has followed the block already.
std::string_view expected_text(const std::vector<Reading*>& active, std::int64_t time,
                               std::vector<char>& buffer) {
  if (std::any_of(active.begin(), active.end(), [](const Reading* r) { return r->followed; }))
    return {};
  const Particles* state = nullptr;
  bool one = true;
  for (Reading* r : active) {
    const Particles* expected = r->judge.expects();
    one = one && expected && (!state || expected == state);
    state = expected;
  }
  return one && state ? print_state_lines(buffer, time, *state) : std::string_view();
}

// Judges `group`, readings that have all taken the same blocks, from one read of the output, each
// part of a block by every active reading before the next part: a reading whose standing falls
// behind is set aside before it pays for the model's step. Stops when every reading is finished
// or set aside.
void judge_together(OutputSource& source, const Scene& scene, std::vector<Reading*> active,
                    const std::optional<Standing>& bound) {
  const std::unique_ptr<OutputReader> reader = source.read(scene);
  const std::uint64_t from = active.front()->taken;
  Block previous, block;
  try {
    // What the group has taken is read again, the last block kept as the next one's previous.
    for (std::uint64_t k = 0; k < from; ++k) reader->next(previous);
    if (from == 0) {
      reader->next(previous);
      for (Reading* r : active) {
        r->judge.start(previous, reader->final_only());
        r->taken = 1;
      }
    }
    // A block that is the text the readings expect is taken as read (most blocks of an output
    // that follows the reference); the one before a block that is not is read from that text.
    std::vector<char> expected, previous_expected;
    std::string_view want, previous_want;
    while (!active.empty() &&
           reader->next(block, want = expected_text(active, previous.time + 1, expected))) {
      if (previous.as_expected && !block.as_expected) reader->read_printed(previous, previous_want);
      for (Reading* r : active) {
        if (!r->followed) r->judge.follow(block);
        r->followed = true;
      }
      set_aside(active, bound);
      for (Reading* r : active) {
        r->judge.judge(block, previous);
        ++r->taken;
        r->followed = false;
      }
      set_aside(active, bound);
      std::swap(previous, block);
      std::swap(expected, previous_expected);
      previous_want = want;
    }
    for (Reading* r : active) r->judge.end(reader->final_repeated());
  } catch (const MalformedOutput& e) {
    for (Reading* r : active) r->judge.malformed(e);
  }
}

// The readings set aside whose standing can still tie or beat the best finished one are taken up
// again, one by one, from where they stopped; the others can only end worse.
void finish_contenders(OutputSource& source, const Scene& scene, std::deque<Reading>& readings) {
  for (;;) {
    std::optional<Standing> best;
    for (const Reading& r : readings)
      if (r.judge.finished())
        best = std::min(best.value_or(r.judge.standing()), r.judge.standing());
    const auto contender = std::find_if(readings.begin(), readings.end(), [&](const Reading& r) {
      return !r.judge.finished() && (!best || r.judge.standing() <= *best);
    });
    if (contender == readings.end()) return;
    judge_together(source, scene, {&*contender}, best);
  }
}

// The scene that an output numbering sub-steps follows at K = 1: each sub-step a step of its
// own, each velocity what it moves in one (v / K, as psim's engines divide it: the same doubles).
Scene per_sub_step(Scene scene, int k) {
  for (std::size_t i = 0; i < scene.size(); ++i) {
    scene.particles.vx[i] /= k;
    scene.particles.vy[i] /= k;
  }
  scene.steps *= k;
  return scene;
}

}  // namespace

Report run_check(const CheckRequest& asked) {
  std::ifstream in(asked.scene, std::ios::binary);
  if (!in)
    throw InputError(fmt::format("{}: cannot open: {}", asked.scene, std::strerror(errno)));
  const Scene read = read_scene(in, asked.scene, RandomInit{});
  check_representable(read, asked.slow_factor, asked.scene);
  CheckRequest request = asked;
  if (asked.sub_steps_numbered) request.slow_factor = 1;
  const Scene scene = asked.sub_steps_numbered ? per_sub_step(read, asked.slow_factor) : read;
  const auto said = [&](Report report) {
    report.reading_required = request.wall_stop.has_value();
    report.overlap_required = request.overlap.has_value();
    if (asked.sub_steps_numbered)
      report.notes.insert(
          report.notes.begin(),
          fmt::format("sub-steps numbered: the output prints each of the K = {} sub-steps of a "
                      "time unit as a step of its own, numbered 0 to {}, velocities per "
                      "sub-step; judged as the scene at K = 1 with velocities / {} over {} "
                      "steps: step n here is time n / {} of the scene",
                      asked.slow_factor, scene.steps, asked.slow_factor, scene.steps,
                      asked.slow_factor));
    return report;
  };
  // Every reading the specification allows, unless one is required; the output is judged by the
  // one it follows best, and nothing counts against it that some reading allows.
  std::vector<WallStop> wall_stops(std::begin(kWallStops), std::end(kWallStops));
  if (request.wall_stop) wall_stops = {*request.wall_stop};
  std::vector<Overlap> overlaps(std::begin(kOverlaps), std::end(kOverlaps));
  if (request.overlap) overlaps = {*request.overlap};
  SharedChunks shared;
  std::deque<Reading> readings;  // in place: a judge holds references to its own state
  for (const WallStop wall_stop : wall_stops)
    for (const Overlap overlap : overlaps)
      readings.emplace_back(request, scene, StepRules{request.slow_factor, wall_stop, overlap},
                            shared);
  OutputSource source(request.output, readings.size() > 1);
  std::vector<Reading*> all;
  for (Reading& r : readings) all.push_back(&r);
  judge_together(source, scene, all, std::nullopt);
  Reading& first = readings.front();
  const bool malformed = std::any_of(readings.begin(), readings.end(), [](const Reading& r) {
    return r.judge.finished() && r.judge.report().verdict == Verdict::malformed;
  });
  if (malformed) {
    // The format is every reading's, broken at the same line: the first reading's report.
    if (!first.judge.finished()) judge_together(source, scene, {&first}, std::nullopt);
    Report report = said(first.judge.report());
    // A program built for K that counts its own sub-steps is malformed at its first sub-step
    // line: where the output can be read again (a file), say what it is when read so.
    if (asked.slow_factor > 1 && !asked.sub_steps_numbered && asked.output != "-") {
      CheckRequest numbered = asked;
      numbered.sub_steps_numbered = true;
      const Report as_sub_steps = run_check(numbered);
      if (as_sub_steps.verdict != Verdict::malformed)
        report.malformed += fmt::format(
            " (read as an output that numbers sub-steps, it is {}: --sub-steps-numbered)",
            to_string(as_sub_steps.verdict));
    }
    return report;
  }
  finish_contenders(source, scene, readings);
  // The best standing, the first reading of those that tie; of each kind, a reading is named
  // "either" where readings of both values tie: the output does not tell them apart.
  const Reading* best = nullptr;
  for (const Reading& r : readings)
    if (r.judge.finished() && (!best || r.judge.standing() < best->judge.standing())) best = &r;
  Report report = said(best->judge.report());
  for (const Reading& r : readings) {
    if (!r.judge.finished() || r.judge.standing() != best->judge.standing()) continue;
    if (r.rules.wall_stop != best->rules.wall_stop) report.reading = "either";
    if (r.rules.overlap != best->rules.overlap) report.overlap = "either";
  }
  return report;
}

int check_main(int argc, char** argv) {
  CLI::App app{
      "psim check: whether OUTPUT, another program's output for SCENE (2019 format; OUTPUT - is "
      "stdin), follows the model; exit 0 exact, consistent or ambiguous, 1 violations, 2 "
      "malformed or bad input",
      "psim check"};
  CheckRequest request;
  std::string slow_factor, wall_stop, overlap, json;
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
  app.add_option("--overlap", overlap,
                 "the overlap reading the output must follow, approaching or always (default: "
                 "either; the report names the one it follows)")
      ->type_name("READING");
  app.add_flag("--sub-steps-numbered", request.sub_steps_numbered,
               "the output numbers sub-steps (every one printed, the last S x K, velocities per "
               "sub-step), as a program built for K does that counts its own sub-steps");
  app.add_option("--json", json, "also write the full report as JSON to FILE")->type_name("FILE");
  try {
    app.parse(argc, argv);
    if (!slow_factor.empty()) request.slow_factor = lab::slow_factor_option(slow_factor);
    if (request.sub_steps_numbered && request.slow_factor == 1)
      throw InputError("--sub-steps-numbered: needs --slow-factor K above 1 (at K = 1 every "
                       "sub-step is a time unit)");
    if (app.count("--wall-stop")) request.wall_stop = lab::wall_stop_option(wall_stop);
    if (app.count("--overlap")) request.overlap = lab::overlap_option(overlap);
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
