// libFuzzer target: the scene parser, then a short differential run of every exact engine.
//
// The input is a scene in the 2019 text format; its last bytes (FuzzedDataProvider takes integers
// from the end) choose K and G, so the files of scenes/ are seeds as they are. One thread: the
// coverage libFuzzer feeds back must not depend on how threads were scheduled, or the inputs it
// tries differ from run to run (CI's fixed seed would not fix them; issue 39). Bit-identity
// across thread counts is the determinism tests' (tests/engine).
// Bad text must end in InputError, never a crash. A scene that parses runs through every engine
// the library declares exact (particle/describe.hpp): those that match the reference must give its
// state bit for bit, and every one must keep the state finite. N, S and K are bounded, and for the
// event engine the number of box crossings, so that one input runs in milliseconds.
#include <fuzzer/FuzzedDataProvider.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/simulation.hpp"

namespace {

constexpr std::int64_t kMaxN = 48;     // particles
constexpr std::int64_t kMaxSteps = 8;  // time units

// N is the first line; a larger one is skipped before read_scene allocates for it (the parser
// accepts up to 1e8). A first line that is no number goes to read_scene, which must reject it.
bool small_enough(const std::string& text) {
  std::int64_t n = 0;
  const std::size_t eol = text.find('\n');
  const char* at = text.data();
  const char* end = at + (eol == std::string::npos ? text.size() : eol);
  while (at < end && (*at == ' ' || *at == '\t' || *at == '+')) ++at;
  const auto [stop, ec] = std::from_chars(at, end, n);
  return ec != std::errc() || n <= kMaxN;
}

// The event engine does work in proportion to the collisions, which no bound on N and S limits:
// a fast particle in a small box is a run of billions of wall hits (fuzz_scene timed out on one
// at 7.8e9 per time unit). Such a run is long, not hung; beyond this budget of box crossings
// (particle::box_crossings, the bound by which the engine refuses 2^40 of them) the
// continuous-time engine is skipped.
constexpr double kMaxCrossings = 1e5;

bool finite(const particle::Particles& p) {
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!std::isfinite(p.x[i]) || !std::isfinite(p.y[i]) || !std::isfinite(p.vx[i]) ||
        !std::isfinite(p.vy[i]))
      return false;
  return true;
}

[[noreturn]] void fail(const char* what, std::string_view engine) {
  std::fprintf(stderr, "fuzz_scene: %s: engine %.*s\n", what, static_cast<int>(engine.size()),
               engine.data());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  particle::RunOptions options;
  options.slow_factor = 1 << in.ConsumeIntegralInRange(0, 3);
  options.grid = in.ConsumeIntegralInRange(1, 16);
  options.threads = 1;
  const std::string text = in.ConsumeRemainingBytesAsString();
  if (!small_enough(text)) return 0;

  particle::Scene scene;
  try {
    std::istringstream stream(text);
    scene = particle::read_scene(stream, "fuzz", {});
  } catch (const particle::InputError&) {
    return 0;  // rejected with a message: what the parser must do with bad text
  }
  if (scene.steps > kMaxSteps) scene.steps = kMaxSteps;

  std::uint64_t reference_hash = 0;
  bool have_reference = false;
  for (const std::string& name : particle::runnable_engines()) {
    const particle::EngineInfo& engine = *particle::find_engine_info(name);
    if (!engine.exact) continue;
    if (engine.continuous_time && !(particle::box_crossings(scene) <= kMaxCrossings)) continue;
    particle::Scene run = scene;
    options.engine = name;
    try {
      particle::simulate(run, options);
    } catch (const particle::InputError&) {
      return 0;  // not representable in doubles: check_representable said so with a message
    }
    if (!finite(run.particles)) fail("state not finite", engine.name);
    if (!engine.matches_reference) continue;
    const std::uint64_t hash = particle::state_hash(run.particles);
    if (have_reference && hash != reference_hash)
      fail("state differs from the others", engine.name);
    reference_hash = hash;
    have_reference = true;
  }
  return 0;
}
