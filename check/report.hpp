#pragma once
// What `psim check` found: the verdict, the steps rounding explains, the violations (the first
// ones in full, a count per kind), and the report as text and JSON.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "whole_file.hpp"

namespace particle::check {

enum class Verdict { exact, consistent, ambiguous, violations, malformed };
std::string_view to_string(Verdict verdict);
// 0 for exact, consistent and ambiguous; 1 for violations; 2 for malformed.
int exit_status(Verdict verdict);

struct Violation {
  std::int64_t step = 0;  // the time unit whose printed state breaks the model
  std::vector<std::uint32_t> particles;
  std::string kind;       // "wall hit missed", "two collisions in one step", ...
  std::string detail;     // what the model does there and what the program printed
  double difference = 0;  // the largest difference of a printed value from the model's
};

struct AmbiguousStep {
  std::int64_t step = 0;
  std::vector<std::uint32_t> particles;
  double difference = 0;
  std::string detail;
};

struct Report {
  std::string scene, output;
  std::int64_t n = 0, steps = 0;
  int slow_factor = 1;
  bool print_mode = true;
  // Perf mode: the output held the final state alone, without the step-0 block (both layouts
  // are the 2019 format's: docs/psim.md, "Output").
  bool final_only = false;
  // Print mode: the output printed its last time unit twice, after its step and then with its
  // counts (both layouts are the 2019 format's: docs/psim.md, "Output").
  bool final_repeated = false;
  // The wall-stop reading that judged it ("per-coordinate", "whole-motion"), or "either" when
  // every reading judges it alike; required: the request named it. The same for the overlap
  // reading ("approaching", "always", "either").
  std::string reading;
  bool reading_required = false;
  std::string overlap;
  bool overlap_required = false;
  Verdict verdict = Verdict::exact;
  std::string summary;                                 // one line, after the verdict
  std::int64_t exact_steps = 0, consistent_steps = 0;  // time units of each kind
  std::vector<AmbiguousStep> ambiguous;
  std::vector<Violation> violations;  // the first kListed in full
  std::map<std::string, std::int64_t> kinds;
  std::int64_t violation_count = 0;
  std::int64_t malformed_line = 0;
  std::string malformed;
  std::vector<std::string> notes;
  double largest_tolerance = 0;  // the largest per-particle tolerance a step allowed

  static constexpr std::size_t kListed = 20;
  void add(Violation v);
};

std::string to_text(const Report& report);

// The ambiguous time units to_text lists (the JSON has them all).
inline constexpr std::size_t kAmbiguousShown = 3;

// "particle 52" or "particles 3, 9" (the first 8, then how many in all).
std::string particles_phrase(const std::vector<std::uint32_t>& particles);
std::string to_json(const Report& report);
// Writes the JSON through psim's one rule for output files (whole or absent; a device, FIFO or
// link's target written in place).
void write_json(const Report& report, lab::WholeFile& file);

}  // namespace particle::check
