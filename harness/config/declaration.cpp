#include "config/declaration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace psweep {
namespace {

const Json& field(const Json& obj, const char* key, const std::string& where) {
  if (!obj.is_object() || !obj.contains(key))
    throw std::runtime_error(fmt::format("{}: missing \"{}\"", where, key));
  return obj[key];
}

std::string text(const Json& obj, const char* key, const std::string& where) {
  const Json& v = field(obj, key, where);
  if (!v.is_string()) throw std::runtime_error(fmt::format("{}.{}: expected a string", where, key));
  return v.get<std::string>();
}

const Json& array(const Json& obj, const char* key, const std::string& where) {
  const Json& v = field(obj, key, where);
  if (!v.is_array()) throw std::runtime_error(fmt::format("{}.{}: expected an array", where, key));
  return v;
}

MetricType metric_type(const std::string& name, const std::string& where) {
  if (name == "real") return MetricType::real;
  if (name == "count") return MetricType::count;
  if (name == "flag") return MetricType::flag;
  throw std::runtime_error(fmt::format("{}.type: unknown type \"{}\"", where, name));
}

double nanoseconds(const Json& v, const std::string& where, const char* key) {
  if (!v.is_number() || v.get<double>() < 0)
    throw std::runtime_error(
        fmt::format("{}.{}: expected a number of nanoseconds >= 0, got {}", where, key, v.dump()));
  return v.get<double>();
}

}  // namespace

bool EngineFacts::uses_param(const std::string& key) const {
  return std::find(uses.begin(), uses.end(), key) != uses.end();
}

const EngineFacts* Declaration::engine(const std::string& name) const {
  for (const EngineFacts& e : engines)
    if (e.name == name) return &e;
  return nullptr;
}

const EngineFacts* Declaration::runnable(const Config& config, const std::string& name) const {
  const Program* program = config.program(name);
  return program ? &program->facts : engine(name);
}

int parse_growth(const std::string& text, const std::string& where) {
  if (text == "N") return 1;
  if (text == "N^2") return 2;
  throw std::runtime_error(
      fmt::format("{}.growth: unknown growth \"{}\" (expected N or N^2)", where, text));
}

std::vector<std::string> Declaration::engine_names() const {
  std::vector<std::string> names;
  for (const EngineFacts& e : engines) names.push_back(e.name);
  return names;
}

Declaration parse_declaration(const std::string& input) {
  Declaration d;
  try {
    d.json = Json::parse(input);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("not JSON: ") + e.what());
  }
  for (const Json& p : array(d.json, "params", "describe")) {
    std::string key = text(p, "key", "params[]");
    if (std::find(param_keys().begin(), param_keys().end(), key) == param_keys().end() ||
        !ignorable_param(key))
      throw std::runtime_error(
          fmt::format("params: \"{}\" is not a parameter psweep can leave out", key));
    d.params.push_back(std::move(key));
  }
  for (const Json& e : array(d.json, "engines", "describe")) {
    EngineFacts f;
    f.name = text(e, "name", "engines[]");
    const std::string where = "engine " + f.name;
    for (const Json& key : array(e, "uses", where)) {
      if (!key.is_string() ||
          std::find(d.params.begin(), d.params.end(), key.get<std::string>()) == d.params.end())
        throw std::runtime_error(
            fmt::format("{}.uses: {} is not a declared parameter", where, key.dump()));
      f.uses.push_back(key.get<std::string>());
    }
    // Optional: a declaration without it (an older psim) estimates every engine as N.
    if (e.contains("growth")) f.growth = parse_growth(text(e, "growth", where), where);
    for (auto [key, value] : {std::pair{"cost_ns", &f.cost_ns}, {"neighbour_ns", &f.neighbour_ns}})
      if (e.contains(key)) *value = nanoseconds(field(e, key, where), where, key);
    // Optional too: an older psim declares no engine it cannot run.
    if (e.contains("unavailable"))
      if (std::string why = text(e, "unavailable", where); !why.empty())
        d.unavailable.emplace(f.name, std::move(why));
    d.engines.push_back(std::move(f));
  }
  for (const Json& m : array(d.json, "metrics", "describe")) {
    MetricFacts f;
    f.key = text(m, "key", "metrics[]");
    const std::string where = "metric " + f.key;
    f.section = text(m, "section", where);
    f.kind = text(m, "kind", where);
    f.type = metric_type(text(m, "type", where), where);
    d.metrics.push_back(std::move(f));
  }
  return d;
}

}  // namespace psweep
