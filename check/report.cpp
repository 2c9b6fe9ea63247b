#include "report.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace particle::check {

std::string_view to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::exact:
      return "exact";
    case Verdict::consistent:
      return "consistent";
    case Verdict::ambiguous:
      return "ambiguous";
    case Verdict::violations:
      return "violations";
    case Verdict::malformed:
      return "malformed";
  }
  return "?";
}

int exit_status(Verdict verdict) {
  return verdict == Verdict::malformed ? 2 : (verdict == Verdict::violations ? 1 : 0);
}

void Report::add(Violation v) {
  ++violation_count;
  ++kinds[v.kind];
  if (violations.size() < kListed) violations.push_back(std::move(v));
}

std::string particles_phrase(const std::vector<std::uint32_t>& particles) {
  if (particles.empty()) return "the whole state";  // energy: no one particle is at fault
  std::string list;
  for (std::size_t k = 0; k < particles.size() && k < 8; ++k)
    list += fmt::format("{}{}", k ? ", " : "", particles[k]);
  if (particles.size() > 8) list += fmt::format(", ... ({} in all)", particles.size());
  return fmt::format("particle{} {}", particles.size() == 1 ? "" : "s", list);
}

std::string to_text(const Report& r) {
  if (r.verdict == Verdict::malformed)
    return fmt::format("verdict: malformed: {}\n  {}\n", r.summary, r.malformed);
  std::string text = fmt::format("verdict: {}, {} reading{}, overlap {}{}: {}\n",
                                 to_string(r.verdict), r.reading,
                                 r.reading_required ? " (required)" : "", r.overlap,
                                 r.overlap_required ? " (required)" : "", r.summary);
  for (const std::string& note : r.notes) text += fmt::format("note: {}\n", note);
  // Violations first: they decide the verdict; then how many time units are ambiguous, with the
  // first few, since a dense scene has many and each is only a near-tie.
  if (r.violation_count > 0) {
    text += fmt::format("violations: {}\n", r.violation_count);
    for (const auto& [kind, count] : r.kinds) text += fmt::format("  {:6} {}\n", count, kind);
    for (const Violation& v : r.violations)
      text += fmt::format("  step {}: {}: {}: {} (off by {:.3g})\n", v.step,
                          particles_phrase(v.particles), v.kind, v.detail, v.difference);
    if (r.violation_count > static_cast<std::int64_t>(r.violations.size()))
      text += fmt::format("  ... {} more (all counted above by kind)\n",
                          r.violation_count - static_cast<std::int64_t>(r.violations.size()));
  }
  if (!r.ambiguous.empty()) {
    text += fmt::format(
        "ambiguous (the print rounding, or a contact at the step's end): {} time unit{}{}\n",
        r.ambiguous.size(), r.ambiguous.size() > 1 ? "s" : "",
        r.ambiguous.size() > kAmbiguousShown ? fmt::format(", the first {}", kAmbiguousShown) : "");
    for (std::size_t k = 0; k < r.ambiguous.size() && k < kAmbiguousShown; ++k)
      text += fmt::format("  step {}: {}: {}\n", r.ambiguous[k].step,
                          particles_phrase(r.ambiguous[k].particles), r.ambiguous[k].detail);
  }
  return text;
}

std::string to_json(const Report& r) {
  nlohmann::json j;
  j["verdict"] = to_string(r.verdict);
  j["summary"] = r.summary;
  j["scene"] = r.scene;
  j["output"] = r.output;
  j["N"] = r.n;
  j["S"] = r.steps;
  j["slow_factor"] = r.slow_factor;
  j["mode"] = r.print_mode ? "print" : "perf";
  if (!r.print_mode)
    j["layout"] = r.final_only ? "final state alone" : "step 0, then the final state";
  else
    j["layout"] = r.final_repeated ? "every time unit, then the final state again with its counts"
                                   : "every time unit, the last with its counts";
  j["exit_status"] = exit_status(r.verdict);
  j["reading"] = r.reading;
  j["reading_required"] = r.reading_required;
  j["overlap"] = r.overlap;
  j["overlap_required"] = r.overlap_required;
  if (r.verdict == Verdict::malformed) {
    j["malformed"] = {{"line", r.malformed_line}, {"message", r.malformed}};
    return j.dump(2) + "\n";
  }
  j["exact_steps"] = r.exact_steps;
  j["consistent_steps"] = r.consistent_steps;
  j["largest_tolerance"] = r.largest_tolerance;
  j["notes"] = r.notes;
  j["ambiguous"] = nlohmann::json::array();
  for (const AmbiguousStep& a : r.ambiguous)
    j["ambiguous"].push_back({{"step", a.step},
                              {"particles", a.particles},
                              {"difference", a.difference},
                              {"detail", a.detail}});
  j["violation_count"] = r.violation_count;
  j["kinds"] = r.kinds;
  j["violations"] = nlohmann::json::array();
  for (const Violation& v : r.violations)
    j["violations"].push_back({{"step", v.step},
                               {"particles", v.particles},
                               {"kind", v.kind},
                               {"detail", v.detail},
                               {"difference", v.difference}});
  return j.dump(2) + "\n";
}

void write_json(const Report& report, lab::WholeFile& file) {
  const std::string text = to_json(report);
  if (std::fwrite(text.data(), 1, text.size(), file.get()) != text.size())
    throw std::runtime_error(
        fmt::format("--json: cannot write {}: {}", file.path(), std::strerror(errno)));
  file.commit();
}

}  // namespace particle::check
