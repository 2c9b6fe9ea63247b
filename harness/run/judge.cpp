// Judge: see judge.hpp.
#include "run/judge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "config/config.hpp"
#include "run/command.hpp"
#include "run/record.hpp"

namespace psweep {
namespace {

// A CSV cell of one line: control characters as spaces, at most `max_chars`.
std::string one_line(const std::string& text, std::size_t max_chars = 300) {
  std::string line = error_tail(text, SIZE_MAX);
  if (line.size() > max_chars) line = line.substr(0, max_chars - 3) + "...";
  return line;
}

}  // namespace

Judgement read_judgement(const std::string& report_json, const ChildResult& child) {
  Judgement j;
  j.seconds = child.process_s;
  const auto unjudged = [&](const std::string& why) {
    j.verdict = "error";
    j.detail = one_line(with_tail("psim check: " + why, child));
    return j;
  };
  if (child.outcome == Outcome::timed_out) return unjudged("exceeded the sweep's timeout_s");
  if (child.outcome != Outcome::exited)
    return unjudged(fmt::format("killed by signal {}", child.signal));
  try {
    const nlohmann::json report = nlohmann::json::parse(report_json);
    j.verdict = report.at("verdict").get<std::string>();
    std::string detail = report.at("summary").get<std::string>();
    // The readings that judged it (docs/check.md, "Readings"), as psim check's text says them;
    // none in a malformed one.
    if (report.contains("reading"))
      detail = fmt::format("{} reading{}, overlap {}{}: {}", report.at("reading").get<std::string>(),
                           report.value("reading_required", false) ? " (required)" : "",
                           report.at("overlap").get<std::string>(),
                           report.value("overlap_required", false) ? " (required)" : "", detail);
    if (j.verdict == "malformed") {
      const auto& m = report.at("malformed");
      detail = fmt::format("line {}: {}", m.at("line").get<std::int64_t>(),
                           m.at("message").get<std::string>());
    } else if (j.verdict == "violations" && !report.at("violations").empty()) {
      const auto& first = report.at("violations").front();
      j.first_step = fmt::format("{}", first.at("step").get<std::int64_t>());
      detail += ": " + first.at("detail").get<std::string>();
    }
    j.detail = one_line(detail);
    return j;
  } catch (const nlohmann::json::exception&) {
    return unjudged(fmt::format("no report (exit status {})", child.exit_code));
  }
}

Judge psim_judge(const std::string& psim, double timeout_s, RequiredReadings reading,
                 std::vector<std::string> sub_steps_numbered) {
  return [psim, timeout_s, reading = std::move(reading), env = current_environment(),
          numbered = std::move(sub_steps_numbered)](const RunSpec& run, const std::string& scene,
                                                    const std::string& output,
                                                    const std::string& report) {
    std::filesystem::remove(report);
    const bool sub_steps = std::find(numbered.begin(), numbered.end(), run.params.engine) !=
                           numbered.end();
    const ChildResult child =
        run_child(check_arguments(run, psim, scene, output, report, reading, sub_steps), env,
                  timeout_s, nullptr);
    return read_judgement(std::filesystem::exists(report) ? read_file(report) : "", child);
  };
}

}  // namespace psweep
