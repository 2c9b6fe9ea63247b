#pragma once
// CLI11's parse errors in the lab's voice, for psim and psweep alike: "--metrics: given twice"
// rather than "At Most 1 required but received 2". Header-only, as CLI11 is.
#include <CLI/CLI.hpp>
#include <regex>
#include <string>
#include <string_view>
#include <utility>

namespace lab {

inline std::string usage_message(const CLI::ParseError& error, std::string_view program) {
  // CLI11 2.1's wordings (CLI/Error.hpp), each with what the lab says instead.
  static const std::pair<std::regex, const char*> rewordings[] = {
      {std::regex("(.*): At Most 1 required but received (\\d+)"), "$1: given $2 times; give it once"},
      {std::regex("(.*): At Most (\\d+) required but received (\\d+)"),
       "$1: expected $2 values, got $3 (given more than once?)"},
      {std::regex("(.*): At least (\\d+) required but received (\\d+)"),
       "$1: expected at least $2 values, got $3"},
      {std::regex("(.*): (\\d+) required (.*) missing"), "$1: expected $3 after it"},
      {std::regex("Expected exactly (\\d+) arguments to (.*), got (\\d+)"),
       "$2: expected $1 values, got $3"},
      {std::regex("Expected at least (\\d+) arguments to (.*), got (\\d+)"),
       "$2: expected at least $1 values, got $3"},
      {std::regex("(.*) is required"), "$1 is missing"},
      {std::regex("The following arguments? (?:was|were) not expected: (.*)"),
       "not an option or argument here: $1"},
      {std::regex("(.*): too many inputs for a flag"), "$1: takes no value"},
      {std::regex("(.*): Should be true/false or a number"), "$1: takes no value"},
      {std::regex("(.*) requires (.*)"), "$1: only together with $2"},
  };
  std::string text = error.what();
  for (const auto& [pattern, wording] : rewordings)
    if (std::regex_match(text, pattern)) {
      text = std::regex_replace(text, pattern, wording);
      break;
    }
  return text + " (" + std::string(program) + " --help lists the options)";
}

}  // namespace lab
