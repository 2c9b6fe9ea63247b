// Tier: see tier.hpp.
#include "run/tier.hpp"

#include <fmt/format.h>

#include "run/confine.hpp"
#include "run/contain.hpp"

namespace psweep {

std::unique_ptr<Tier> strongest_tier(const std::vector<std::string>& hide, std::string& why) {
  std::string no_bwrap, no_landlock;
  if (auto tier = bwrap_tier(hide, no_bwrap)) return tier;
  if (auto tier = contained_tier(no_landlock)) {
    why = no_bwrap;  // said when the weaker tier is chosen
    return tier;
  }
  why = fmt::format("{}; and without namespaces, {}", no_bwrap, no_landlock);
  return nullptr;
}

}  // namespace psweep
