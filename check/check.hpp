#pragma once
// `psim check SCENE OUTPUT`: whether another program's output for a scene follows the model
// (docs/check.md).
#include <optional>
#include <string>

#include "particle/options.hpp"
#include "report.hpp"

namespace particle::check {

struct CheckRequest {
  std::string scene, output;  // paths; output "-" is stdin
  int slow_factor = 1;
  // The wall-stop reading the output must follow; none: every reading is tried, and the one it
  // follows best judges it (docs/check.md, "Readings").
  std::optional<WallStop> wall_stop;
  // The overlap reading it must follow, the same way.
  std::optional<Overlap> overlap;
  // The output numbers sub-steps, not time units: every sub-step printed (in print mode), the
  // last numbered S x K, velocities per sub-step (v / K), as the 2019 authors' parallel-2 prints
  // them. Judged as the scene it simulates: velocities / K over S x K steps at K = 1.
  bool sub_steps_numbered = false;
};

// Reads the scene (psim's reader and messages: InputError) and judges the output. A malformed
// output is a verdict, not an exception.
Report run_check(const CheckRequest& request);

// The command line after `psim`: argv[0] is "check". Prints the report; returns the exit status
// (0 exact, consistent or ambiguous; 1 violations; 2 malformed output or bad usage).
int check_main(int argc, char** argv);

}  // namespace particle::check
