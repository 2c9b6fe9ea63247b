#include "engines.hpp"

#include <array>
#include <string>

#include "broad_phase_brute.hpp"

namespace particle {
namespace detail {
namespace {

// `auto` picks the cheapest correct engine for the scene; brute is the only one so far.
constexpr std::array kEngines = {
    EngineEntry{"auto", run_brute},
    EngineEntry{"brute", run_brute},
};

}  // namespace

RunReport run_brute(const World& w, const RunOptions&, const PipelineParams& params) {
  BruteBroadPhase broad;
  return run_pipeline(broad, w, params);
}

const EngineEntry* find_engine(std::string_view name) {
  for (const EngineEntry& e : kEngines)
    if (e.name == name) return &e;
  return nullptr;
}

}  // namespace detail

const std::vector<std::string>& engine_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : detail::kEngines) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

bool is_engine(std::string_view name) { return detail::find_engine(name) != nullptr; }

}  // namespace particle
