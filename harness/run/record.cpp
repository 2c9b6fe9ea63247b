#include "run/record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace psweep {

const char* to_string(Status s) {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::failed:
      return "failed";
    case Status::timeout:
      return "timeout";
    case Status::crashed:
      return "crashed";
    case Status::too_much_output:
      return "too_much_output";
  }
  return "?";
}

namespace {

// One declared metric's CSV cell; empty when the object lacks it.
std::string metric_cell(const nlohmann::json& obj, const MetricFacts& m, const std::string& path) {
  if (!obj.contains(m.key) || obj[m.key].is_null()) return {};
  const auto& v = obj[m.key];
  switch (m.type) {
    case MetricType::real:
      if (!v.is_number()) throw std::runtime_error(fmt::format("{}: expected a number", path));
      return fmt::format("{}", v.get<double>());
    case MetricType::count:
      if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0))
        throw std::runtime_error(fmt::format("{}: expected a non-negative integer", path));
      return fmt::format("{}", v.get<std::uint64_t>());
    case MetricType::flag:
      if (!v.is_boolean())
        throw std::runtime_error(fmt::format("{}: expected true or false", path));
      return v.get<bool>() ? "1" : "0";
  }
  return {};
}

}  // namespace

std::string Metrics::value(const std::string& key) const {
  auto found = values.find(key);
  return found == values.end() ? std::string() : found->second;
}

Metrics parse_metrics(const std::string& text, const Declaration& declaration) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(std::string("not JSON: ") + e.what());
  }
  if (!j.is_object()) throw std::runtime_error("not a JSON object");
  Metrics m;
  if (j.contains("engine")) {
    if (!j["engine"].is_string()) throw std::runtime_error("engine: expected a string");
    m.engine = j["engine"].get<std::string>();
  }
  if (j.contains("wall_s") && !j["wall_s"].is_null()) {
    if (!j["wall_s"].is_number()) throw std::runtime_error("wall_s: expected a number");
    m.wall_s = j["wall_s"].get<double>();
  }
  if (j.contains("state_hash")) {
    if (!j["state_hash"].is_string()) throw std::runtime_error("state_hash: expected a string");
    m.state_hash = j["state_hash"].get<std::string>();
  }
  for (const MetricFacts& metric : declaration.metrics) {
    const nlohmann::json* obj = &j;
    std::string path = metric.key;
    if (!metric.section.empty()) {
      if (!j.contains(metric.section)) continue;
      obj = &j[metric.section];
      if (!obj->is_object())
        throw std::runtime_error(fmt::format("{}: expected an object", metric.section));
      path = metric.section + "." + metric.key;
    }
    if (auto cell = metric_cell(*obj, metric, path); !cell.empty())
      m.values[metric.key] = std::move(cell);
  }
  if (j.contains("cpus")) {
    if (!j["cpus"].is_array()) throw std::runtime_error("cpus: expected an array");
    for (const auto& cpu : j["cpus"]) {
      if (!cpu.is_number_integer()) throw std::runtime_error("cpus: expected integers");
      m.cpus.push_back(cpu.get<int>());
    }
  }
  return m;
}

std::string with_tail(const std::string& what, const ChildResult& child) {
  const std::string tail = error_tail(child.stderr_tail);
  return tail.empty() ? what : what + ": " + tail;
}

std::string error_tail(const std::string& text, std::size_t max_chars) {
  std::string line;
  std::size_t end = text.size();
  while (end > 0 && (text[end - 1] == '\n' || text[end - 1] == '\r' || text[end - 1] == ' ')) --end;
  for (std::size_t i = 0; i < end; ++i) {
    unsigned char ch = static_cast<unsigned char>(text[i]);
    if (ch == '\n')
      line += " | ";
    else if (ch < 0x20 || ch == 0x7f)
      line += ' ';
    else
      line += static_cast<char>(ch);
  }
  if (line.size() > max_chars) line = "..." + line.substr(line.size() - (max_chars - 3));
  return line;
}

namespace {

// Whole microseconds divided once, so 0.356679 prints as 0.356679 and not 0.35667899999999997.
double seconds(const timeval& tv) {
  return static_cast<double>(tv.tv_sec * 1000000LL + tv.tv_usec) / 1e6;
}

}  // namespace

std::optional<double> Record::wall_s() const {
  if (status != Status::ok) return std::nullopt;
  return program ? std::optional<double>(process_s) : metrics->wall_s;
}

namespace {

// What psweep measured about any child, and its status unless it exited 0 (then `ok`, for the
// caller to confirm).
Record measured(const RunSpec& run, int rep, const ChildResult& child, double timeout_s,
                int online_cores) {
  Record r;
  r.run = &run;
  r.rep = rep;
  r.process_s = child.process_s;
  r.user_s = seconds(child.usage.ru_utime);
  r.sys_s = seconds(child.usage.ru_stime);
  r.max_rss_kb = child.usage.ru_maxrss;  // Linux reports kilobytes
  r.voluntary_switches = child.usage.ru_nvcsw;
  r.involuntary_switches = child.usage.ru_nivcsw;
  r.events = child.events;
  if (!r.events.context_switches)
    r.events.context_switches =
        static_cast<std::uint64_t>(r.voluntary_switches + r.involuntary_switches);
  if (!r.events.page_faults)
    r.events.page_faults =
        static_cast<std::uint64_t>(child.usage.ru_minflt + child.usage.ru_majflt);
  r.oversubscribed = run.params.T && run_threads(run.params) > online_cores;

  switch (child.outcome) {
    case Outcome::timed_out:
    case Outcome::interrupted:  // not recorded by the sweep; described anyway
      r.status = Status::timeout;
      r.error = with_tail(fmt::format("exceeded timeout_s = {}", timeout_s), child);
      return r;
    case Outcome::over_limit:
      r.status = Status::crashed;
      r.error = with_tail(child.over, child);
      return r;
    case Outcome::signaled:
      r.status = Status::crashed;
      r.error = with_tail(
          fmt::format("killed by signal {} ({})", child.signal, strsignal(child.signal)), child);
      return r;
    case Outcome::exited:
      r.exit_code = child.exit_code;
      break;
  }
  if (child.exit_code != 0) {
    r.status = Status::failed;
    const std::string tail = error_tail(child.stderr_tail);
    r.error = tail.empty() ? fmt::format("exit status {}", child.exit_code) : tail;
  }
  return r;
}

}  // namespace

Record make_record(const RunSpec& run, int rep, const ChildResult& child,
                   const std::string& metrics_text, double timeout_s, int online_cores,
                   const Declaration& declaration) {
  Record r = measured(run, rep, child, timeout_s, online_cores);
  if (r.status != Status::ok) return r;
  try {
    if (metrics_text.empty()) throw std::runtime_error("psim wrote no metrics file");
    r.metrics = parse_metrics(metrics_text, declaration);
    if (!r.metrics->wall_s) throw std::runtime_error("the metrics have no wall_s");
  } catch (const std::exception& e) {
    r.status = Status::failed;
    r.error = with_tail(std::string("metrics: ") + e.what(), child);
  }
  return r;
}

Record make_program_record(const RunSpec& run, int rep, const ChildResult& child,
                           std::uint64_t output_bytes, std::uint64_t output_limit, double timeout_s,
                           int online_cores) {
  Record r = measured(run, rep, child, timeout_s, online_cores);
  r.program = true;
  // SIGXFSZ, or a program that ignores it and gives up (or spins until the timeout) when its
  // writes fail: the limit is the cause either way.
  if (output_limit > 0 && output_bytes >= output_limit) {
    r.status = Status::too_much_output;
    r.exit_code.reset();
    r.error = fmt::format(
        "held {} bytes on disk (printed, or reserved with fallocate), where a 2019 output of "
        "this scene takes at most {} (N = {}, S = {}): stopped there",
        output_bytes, output_limit, run.params.N, run.params.S);
  }
  return r;
}

}  // namespace psweep
