// Config parsing: JSON -> Config, every error naming the file and the key's path.
//
// Validation happens per value through set_param, the one place that knows each parameter's type
// and range; base values, sweep values and their defaults all go through it.
#include "config/config.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "config/launcher.hpp"
#include "config/program.hpp"
#include "particle/io.hpp"

namespace psweep {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ConfigError(path + ": " + what);
}

std::int64_t non_negative_integer(const Json& v, const std::string& path) {
  if (v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() >= 0))
    return static_cast<std::int64_t>(v.get<std::uint64_t>() & 0x7fffffffffffffffULL);
  fail(path, "expected a non-negative integer, got " + v.dump());
}

double non_negative_number(const Json& v, const std::string& path) {
  if (v.is_number()) {
    double d = v.get<double>();
    if (std::isfinite(d) && d >= 0) return d;
  }
  fail(path, "expected a non-negative number, got " + v.dump());
}

std::string one_of(const Json& v, const std::string& path,
                   const std::vector<std::string>& allowed) {
  if (v.is_string() &&
      std::find(allowed.begin(), allowed.end(), v.get<std::string>()) != allowed.end())
    return v.get<std::string>();
  fail(path, fmt::format("expected one of \"{}\", got {}", fmt::join(allowed, "\", \""), v.dump()));
}

// nlohmann's message without its "[json.exception.parse_error.101] " tag.
std::string untagged(const nlohmann::json::exception& e) {
  const std::string what = e.what();
  const auto end = what.find("] ");
  return what.rfind("[json.exception.", 0) == 0 && end != std::string::npos ? what.substr(end + 2)
                                                                            : what;
}

// The key path of the value a SAX pass stopped at: nlohmann reports a number out of range
// (1e400) with no position, so the text is walked again keeping the path of keys and indices.
// The walk also stops at a key given twice in one object, which nlohmann's parser takes silently
// (the last wins).
class PathTracker : public nlohmann::json_sax<Json> {
 public:
  bool duplicate() const { return duplicate_; }
  std::string path() const {
    std::string out;
    for (const Frame& f : frames_)
      out += f.array ? fmt::format("[{}]", f.index) : (out.empty() ? "" : ".") + f.key;
    return out.empty() ? "(top level)" : out;
  }

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(false); }
  bool key(string_t& k) override {
    frames_.back().key = k;
    duplicate_ = !frames_.back().keys.insert(k).second;
    return !duplicate_;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  struct Frame {
    bool array;
    std::string key;
    std::size_t index = 0;
    std::set<std::string> keys;  // of an object, so far
  };
  bool value() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  bool open(bool array) {
    frames_.push_back({array, "", 0, {}});
    return true;
  }
  bool close() {
    frames_.pop_back();
    return value();
  }
  std::vector<Frame> frames_;
  bool duplicate_ = false;
};

// The document, or a ConfigError: syntax errors at nlohmann's "line L, column C"; a number out of
// range (no position) at its key path.
Json parse_json(const std::string& text) {
  try {
    Json json = Json::parse(text);
    PathTracker tracker;
    Json::sax_parse(text, &tracker);
    if (tracker.duplicate())
      throw ConfigError(tracker.path() +
                        ": given twice in one object; keep one (JSON would "
                        "silently take the last)");
    return json;
  } catch (const nlohmann::json::parse_error& e) {
    // "parse error at line 3, column 5: <why>"
    std::string why = untagged(e), where;
    if (const auto at = why.find("line "); at != std::string::npos)
      if (const auto colon = why.find(": ", at); colon != std::string::npos) {
        where = why.substr(at, colon - at) + ": ";
        why = why.substr(colon + 2);
      }
    throw ConfigError(where + "invalid JSON: " + why);
  } catch (const nlohmann::json::exception& e) {
    PathTracker tracker;
    Json::sax_parse(text, &tracker);
    std::string why = untagged(e);
    if (why.size() > 80) why = why.substr(0, 76) + "...'";  // a 5000-digit number, cut
    throw ConfigError(tracker.path() + ": " + why + " (beyond the range of a double)");
  }
}

}  // namespace

std::int64_t positive_integer(const Json& v, const std::string& path) {
  if (v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() > 0)) {
    auto u = v.get<std::uint64_t>();
    if (u > 0 && u <= (std::uint64_t{1} << 40)) return static_cast<std::int64_t>(u);
  }
  fail(path, "expected a positive integer, got " + v.dump());
}

double positive_number(const Json& v, const std::string& path) {
  if (v.is_number()) {
    double d = v.get<double>();
    if (std::isfinite(d) && d > 0) return d;
  }
  fail(path, "expected a positive number, got " + v.dump());
}

const char* to_string(Pin pin) {
  switch (pin) {
    case Pin::close:
      return "close";
    case Pin::spread:
      return "spread";
    case Pin::none:
      return "none";
  }
  return "?";
}

const char* to_string(Combine combine) {
  switch (combine) {
    case Combine::product:
      return "product";
    case Combine::one_at_a_time:
      return "one-at-a-time";
    case Combine::zip:
      return "zip";
  }
  return "?";
}

const std::vector<std::string>& param_keys() {
  static const std::vector<std::string> keys = {
      "engine", "N", "L",         "r",         "S",         "slow_factor", "T",
      "P",      "G", "seed",      "speed_min", "speed_max", "neighbour",   "wall_stop",
      "overlap"};
  return keys;
}

OptionalParam optional_param(const std::string& key) {
  if (key == "T") return &Params::T;
  if (key == "P") return &Params::P;
  if (key == "G") return &Params::G;
  if (key == "slow_factor") return &Params::slow_factor;
  return nullptr;
}

bool ignorable_param(const std::string& key) {
  return optional_param(key) != nullptr || key == "wall_stop" || key == "overlap";
}

void set_param(Params& p, const std::string& key, const Json& v, const std::string& path) {
  if (key == "engine") {
    if (!v.is_string() || v.get<std::string>().empty())
      fail(path, "expected an engine name (a string)");
    p.engine = v.get<std::string>();
  } else if (key == "N") {
    p.N = positive_integer(v, path);
  } else if (key == "L") {
    p.L = positive_number(v, path);
  } else if (key == "r") {
    p.r = positive_number(v, path);
  } else if (key == "S") {
    p.S = non_negative_integer(v, path);  // S = 0 writes the initial state, as psim does
  } else if (key == "slow_factor") {
    auto k = v.is_number_integer() ? v.get<std::int64_t>() : 0;
    if (k <= 0 || (k & (k - 1)) != 0 || k > (std::int64_t{1} << 30))
      fail(path, "expected a power of two (1, 2, 4, ...), got " + v.dump());
    p.slow_factor = k;
  } else if (key == "seed") {
    if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0))
      fail(path, "expected a non-negative integer, got " + v.dump());
    p.seed = v.get<std::uint64_t>();
  } else if (key == "T") {
    p.T = positive_integer(v, path);
  } else if (key == "P") {
    p.P = positive_integer(v, path);
    // Every move of the mpi engine is an all-to-all over every rank: it suits a few nodes.
    if (*p.P > kMaxRanks)
      fail(path, fmt::format("expected at most {} ranks, got {}", kMaxRanks, v.dump()));
  } else if (key == "G") {
    p.G = positive_integer(v, path);
  } else if (key == "speed_min") {
    p.speed_min = non_negative_number(v, path);
  } else if (key == "speed_max") {
    p.speed_max = non_negative_number(v, path);
  } else if (key == "neighbour") {
    p.neighbour = one_of(v, path, {"none", "busy"});
  } else if (key == "wall_stop") {
    p.wall_stop = one_of(v, path, {"per-coordinate", "whole-motion"});
  } else if (key == "overlap") {
    p.overlap = one_of(v, path, {"approaching", "always"});
  } else {
    fail(path,
         fmt::format("unknown parameter (expected one of {})", fmt::join(param_keys(), ", ")));
  }
}

std::shared_ptr<const particle::Scene> read_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(fmt::format("scene_file: cannot open \"{}\"", path));
  try {
    // psim's reader: the same rules and messages (a file without particle lines is placed from
    // psim's default seed, as psim places it)
    return std::make_shared<const particle::Scene>(particle::read_scene(in, path, {}));
  } catch (const particle::InputError& e) {
    throw ConfigError(std::string("scene_file: ") + e.what());
  }
}

namespace {

// name: becomes the default results directory, so it must be a plain file name; without it, the
// file's name without its extension.
std::string config_name(const Json& raw, const std::string& file) {
  if (raw.contains("name")) {
    const auto& n = raw["name"];
    bool ok = n.is_string() && !n.get<std::string>().empty() && n.get<std::string>()[0] != '.';
    if (ok)
      for (char ch : n.get<std::string>())
        ok = ok &&
             (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.');
    if (!ok) fail("name", "expected a name of letters, digits, '_', '-' and '.', got " + n.dump());
    return n.get<std::string>();
  }
  auto slash = file.find_last_of('/');
  std::string name = file.substr(slash == std::string::npos ? 0 : slash + 1);
  if (auto dot = name.rfind('.'); dot != std::string::npos && dot > 0) name.resize(dot);
  return name;
}

// The top-level settings (everything but base and sweep); `file` names the default `name`.
void read_settings(Config& c, const std::string& file) {
  static const std::vector<std::string> top_keys = {
      "name",     "description", "base",        "sweep",      "combine",  "repetitions",
      "warmup",   "pin",         "timeout_s",   "scene_file", "max_runs", "analysis",
      "programs", "limits",      "judge_steps", "reading",    "launcher", "counters",
      "quiet_wait_s", "overlap_reading"};
  for (auto& [key, value] : c.raw.items())
    if (std::find(top_keys.begin(), top_keys.end(), key) == top_keys.end())
      fail(key, fmt::format("unknown key (expected one of {})", fmt::join(top_keys, ", ")));

  c.name = config_name(c.raw, file);
  if (c.raw.contains("description") && !c.raw["description"].is_string())
    fail("description", "expected a string");
  // analysis: settings for the tables that read the results (e.g. analysis/targets/); psweep
  // does not read them, meta.json carries them with the rest of the config.
  if (c.raw.contains("analysis") && !c.raw["analysis"].is_object())
    fail("analysis", "expected an object (read by the analysis through meta.json)");
  if (c.raw.contains("combine")) {
    auto combine = one_of(c.raw["combine"], "combine", {"product", "one-at-a-time", "zip"});
    c.combine = combine == "product"         ? Combine::product
                : combine == "one-at-a-time" ? Combine::one_at_a_time
                                             : Combine::zip;
  }
  if (c.raw.contains("pin")) {
    auto pin = one_of(c.raw["pin"], "pin", {"close", "spread", "none"});
    c.pin = pin == "close" ? Pin::close : pin == "spread" ? Pin::spread : Pin::none;
  }
  if (c.raw.contains("repetitions")) {
    auto n = positive_integer(c.raw["repetitions"], "repetitions");
    if (n > 100000) fail("repetitions", "expected at most 100000");
    c.repetitions = static_cast<int>(n);
  }
  if (c.raw.contains("warmup")) {
    auto n = non_negative_integer(c.raw["warmup"], "warmup");
    if (n > 1000) fail("warmup", "expected at most 1000");
    c.warmup = static_cast<int>(n);
  }
  if (c.raw.contains("timeout_s")) {
    c.timeout_s = positive_number(c.raw["timeout_s"], "timeout_s");
    if (c.timeout_s > kMaxTimeoutS)
      fail("timeout_s", fmt::format("expected at most {} (a week), got {}", kMaxTimeoutS,
                                    c.raw["timeout_s"].dump()));
  }
  if (c.raw.contains("quiet_wait_s")) {
    c.quiet_wait_s = non_negative_number(c.raw["quiet_wait_s"], "quiet_wait_s");
    if (c.quiet_wait_s > 3600)
      fail("quiet_wait_s", fmt::format("expected at most 3600 (an hour), got {}",
                                       c.raw["quiet_wait_s"].dump()));
  }
  if (c.raw.contains("max_runs")) c.max_runs = positive_integer(c.raw["max_runs"], "max_runs");
  if (c.raw.contains("scene_file")) {
    const auto& s = c.raw["scene_file"];
    if (!s.is_string() || s.get<std::string>().empty()) fail("scene_file", "expected a file path");
    c.scene_file = s.get<std::string>();
    c.scene = read_scene_file(*c.scene_file);
  }
  if (c.raw.contains("judge_steps"))
    c.judge_steps = positive_integer(c.raw["judge_steps"], "judge_steps");
  if (c.raw.contains("reading"))
    c.reading.wall_stop = one_of(c.raw["reading"], "reading", {"per-coordinate", "whole-motion"});
  if (c.raw.contains("overlap_reading"))
    c.reading.overlap = one_of(c.raw["overlap_reading"], "overlap_reading", {"approaching", "always"});
  if (c.raw.contains("counters"))
    c.simulate_counters =
        one_of(c.raw["counters"], "counters", {"hardware", "simulate"}) == "simulate";
  if (c.raw.contains("limits")) c.limits = parse_limits(c.raw["limits"], "limits", c.limits);
  if (c.raw.contains("programs")) c.programs = parse_programs(c.raw["programs"], c.limits);
  c.launcher = c.raw.contains("launcher") ? parse_launcher(c.raw["launcher"], "launcher")
                                          : default_launcher(geteuid() == 0);
}

// base, with the defaults every run starts from.
void read_base(Config& c) {
  if (!c.raw.contains("base")) fail("base", "missing (the parameters every run starts from)");
  c.base_json = c.raw["base"];
  if (!c.base_json.is_object()) fail("base", "expected an object");
  c.base.slow_factor = 1;
  c.base.T = 1;
  c.base.P = 1;
  if (!c.scene_file) c.base.seed = particle::RandomInit{}.seed;  // psim's default scene seed
  for (auto& [key, value] : c.base_json.items()) set_param(c.base, key, value, "base." + key);
}

// sweep: each axis's values validated one by one.
void read_sweep(Config& c) {
  if (c.raw.contains("sweep")) {
    const auto& sweep = c.raw["sweep"];
    if (!sweep.is_object()) fail("sweep", "expected an object of axis: [values]");
    for (auto& [key, values] : sweep.items()) {
      const std::string path = "sweep." + key;
      if (std::find(param_keys().begin(), param_keys().end(), key) == param_keys().end())
        fail(path,
             fmt::format("unknown parameter (expected one of {})", fmt::join(param_keys(), ", ")));
      if (!values.is_array() || values.empty()) fail(path, "expected a non-empty array of values");
      Axis axis{key, {}};
      Params scratch;
      for (std::size_t i = 0; i < values.size(); ++i) {
        set_param(scratch, key, values[i], fmt::format("{}[{}]", path, i));
        axis.values.push_back(values[i]);
      }
      c.sweep.push_back(std::move(axis));
    }
  }

  // zip pairs the axes element by element (run i takes value i of every axis): a shorter
  // axis would leave runs without a value, so unequal lengths are an error, not a truncation.
  if (c.combine == Combine::zip)
    for (const auto& axis : c.sweep)
      if (axis.values.size() != c.sweep.front().values.size())
        fail("sweep." + axis.key,
             fmt::format("{} values, but sweep.{} has {} (combine \"zip\" pairs the axes "
                         "element by element, so all must have the same length)",
                         axis.values.size(), c.sweep.front().key, c.sweep.front().values.size()));
}

// What only base and sweep together show: a scene given twice, a required parameter missing.
void check_complete(Config& c) {
  auto swept = [&](const std::string& key) {
    return std::any_of(c.sweep.begin(), c.sweep.end(), [&](const Axis& a) { return a.key == key; });
  };
  if (c.scene_file) {
    // The scene file fixes the scene; a second source for the same numbers would be ambiguous.
    for (const char* key : {"N", "L", "r", "S", "seed", "speed_min", "speed_max"}) {
      if (c.base_json.contains(key))
        fail(std::string("base.") + key,
             "not allowed with scene_file (the scene file fixes the scene)");
      if (swept(key))
        fail(std::string("sweep.") + key,
             "not allowed with scene_file (the scene file fixes the scene)");
    }
    c.base.N = static_cast<std::int64_t>(c.scene->size());
    c.base.L = c.scene->L;
    c.base.r = c.scene->r;
    c.base.S = c.scene->steps;
  }
  std::vector<std::string> required = {"engine"};
  if (!c.scene_file) required.insert(required.end(), {"N", "L", "r", "S"});
  for (const auto& key : required) {
    if (c.base_json.contains(key)) continue;
    if (c.combine != Combine::one_at_a_time && swept(key)) continue;
    fail("base." + key, c.combine != Combine::one_at_a_time
                            ? "missing (set it in base or sweep it)"
                            : "missing (one-at-a-time varies axes around base)");
  }
}

}  // namespace

Config parse_config(const std::string& text, const std::string& file) {
  Config c;
  c.file = file;
  try {
    c.raw = parse_json(text);
    if (!c.raw.is_object()) fail("(top level)", "expected a JSON object");
    read_settings(c, file);
    read_base(c);
    read_sweep(c);
    check_complete(c);
  } catch (const ConfigError& e) {
    throw ConfigError(file + ": " + e.what());
  }
  return c;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Config load_config(const std::string& path) {
  if (std::filesystem::is_directory(path))
    throw ConfigError(path + ": is a directory, not a config file (e.g. configs/quick.json)");
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the config file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), path);
}

const Program* Config::program(const std::string& engine) const {
  for (const Program& p : programs)
    if (p.facts.name == engine) return &p;
  return nullptr;
}

void check_engines(const Config& c, const std::vector<std::string>& known,
                   const std::map<std::string, std::string>& unavailable) {
  std::vector<std::string> names;
  for (const Program& p : c.programs) {
    const std::string& name = p.facts.name;
    if (std::find(known.begin(), known.end(), name) != known.end())
      throw ConfigError(fmt::format(
          "{}: programs.{}: shadows psim's engine \"{}\"; give the program another name", c.file,
          name, name));
    names.push_back(name);
  }
  auto check = [&](const Json& v, const std::string& path) {
    auto name = v.get<std::string>();
    if (std::find(known.begin(), known.end(), name) == known.end() && !c.program(name))
      throw ConfigError(fmt::format(
          "{}: {}: unknown engine \"{}\" (psim offers: {}{})", c.file, path, name,
          fmt::join(known, ", "),
          names.empty() ? "" : fmt::format("; the config's programs: {}", fmt::join(names, ", "))));
    if (const auto why = unavailable.find(name); why != unavailable.end())
      throw ConfigError(fmt::format(
          "{}: {}: engine \"{}\" cannot run in this build of psim: {} (psim --describe says "
          "which engines can)",
          c.file, path, name, why->second));
  };
  if (c.base_json.contains("engine")) check(c.base_json["engine"], "base.engine");
  for (const auto& axis : c.sweep)
    if (axis.key == "engine")
      for (std::size_t i = 0; i < axis.values.size(); ++i)
        check(axis.values[i], fmt::format("sweep.engine[{}]", i));
}

}  // namespace psweep
