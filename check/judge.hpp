#pragma once
// One reading's judgement of a program's output (docs/check.md): the printed time units fed in
// order, the verdict after the last. A time unit is taken in two parts: follow(), the invariants
// and whether the output is still the reference's text (a reference step and a comparison), and
// judge(), the model run from the printed state where it is not. run_check (check.cpp) feeds
// every reading from one read of the output, one part at a time, and sets aside a reading whose
// standing is already worse than another's: a standing only gets worse as time units come, so
// such a reading is finished only if the others end worse than it stood.
#include <cstdint>
#include <tuple>
#include <vector>

#include "check.hpp"
#include "particle/output_text.hpp"
#include "particle/particles.hpp"
#include "particle/replay.hpp"
#include "particle/scene.hpp"
#include "reference_run.hpp"
#include "report.hpp"

namespace particle::check {

// How well an output follows a reading, lower is better: the verdict, then fewer violations,
// then fewer time units that only rounding explains.
using Standing = std::tuple<int, std::int64_t, std::size_t>;

class Judge {
 public:
  // rules: the request's K and one reading of each kind.
  Judge(const CheckRequest& request, const Scene& scene, const StepRules& rules,
        SharedChunks& shared);
  Judge(const Judge&) = delete;
  Judge& operator=(const Judge&) = delete;

  // The output's first block (time 0, or the scene's own start where a perf-mode output holds
  // the final state alone).
  void start(const Block& first, bool final_only);
  // Print mode, while the output has printed the reference's text: the state the next block
  // prints if it still does (the reference's next time unit, which follow() then takes); null
  // otherwise. The caller may read the next block as that state's text (Block::as_expected).
  const Particles* expects();
  // A later block, `previous` the one before it: follow() first, then judge().
  void follow(const Block& block);
  void judge(const Block& block, const Block& previous);
  // After the final block: the verdict.
  void end(bool final_repeated);
  // The output breaks the format (every reading's verdict, at the same line).
  void malformed(const MalformedOutput& e);

  // The standing so far: the final one is never better.
  Standing standing() const;
  bool finished() const { return finished_; }
  const Report& report() const { return report_; }

 private:
  void invariants(const Block& block, const Particles& p);
  void model(const Block& block, const Particles& start, bool exact_start);
  void count(const Particles& step_counts);
  void finish(const Block& last);
  void judge_perf_final(const Block& block);

  const Scene& scene_;
  StepRules rules_;
  int k_;
  Report report_;
  SharedChunks& shared_;  // the runs of every reading of this check
  // The reference run from the scene while the output matches it (its counts: expected_*).
  ReferenceRun reference_;
  const Particles* ahead_ = nullptr;  // the reference's next state, taken by expects()
  bool exact_ = true;
  bool followed_reference_ = false;  // the block follow() took is the reference's text
  bool usable_ = true;               // the printed states so far can start the model
  bool perf_exact_ = false;          // perf mode: the final state is the reference run's
  bool finished_ = false;
  std::vector<std::uint64_t> expected_pairs_, expected_walls_, slack_;
  double energy0_;
  bool energy_reported_ = false;
  int detailed_steps_ = 0;
  double order_pair_tests_ = 0;  // spent on the wrong-order test beyond the detailed time units
};

}  // namespace particle::check
