// The real engine library's declaration (what psim --describe prints), for the harness's tests;
// with_event() adds an engine that uses none of T, G, K, as the `event` engine declares.
#pragma once

#include "config/declaration.hpp"
#include "particle/describe.hpp"

namespace psweep::fixture {

inline Declaration engine_declaration() { return parse_declaration(particle::describe_json()); }

// The declaration parsed once for a whole test program.
inline const Declaration& declared() {
  static const Declaration d = engine_declaration();
  return d;
}

inline Declaration with_event() {
  Json json = Json::parse(particle::describe_json());
  bool declared = false;
  for (const auto& e : json["engines"]) declared = declared || e["name"] == "event";
  if (!declared)
    json["engines"].push_back(
        {{"name", "event"}, {"exact", true}, {"reference", false}, {"uses", Json::array()}});
  return parse_declaration(json.dump());
}

}  // namespace psweep::fixture
