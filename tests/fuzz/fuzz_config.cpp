// libFuzzer target: psweep's config parser followed by the expansion into runs.
//
// Any text must end in a list of runs or a ConfigError, never a crash, a hang or an allocation
// without bound. The engine facts are the engine library's own declaration (what psim --describe
// prints), read directly rather than by running psim.
#include <string>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "particle/describe.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const psweep::Declaration declaration =
      psweep::parse_declaration(particle::describe_json());
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const psweep::Config config = psweep::parse_config(text, "fuzz.json");
    // Expanded only up to psweep's default max_runs: a few lines of JSON can ask for 10^9
    // configurations, which psweep refuses from their count without --yes (expansion's own test
    // walks 10^7 in constant memory); expanding them here only times the fuzzer out.
    const auto most = static_cast<std::size_t>(psweep::Config{}.max_runs);
    if (psweep::count_configurations(config, declaration) > most) return 0;
    for (const psweep::RunSpec& run : psweep::expand(config, declaration))
      static_cast<void>(psweep::describe(run));
  } catch (const psweep::ConfigError&) {
    // rejected with a message naming the key: what the parser must do with bad input
  }
  return 0;
}
