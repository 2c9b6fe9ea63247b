#pragma once
// What a scene must satisfy to be simulated in doubles, checked once before anything runs.
//
// The engine works in its own length unit, a power of two chosen per scene (scale.hpp), so the
// absolute size of a scene does not matter: a scene scaled by 2^k gives the result scaled by 2^k,
// bit for bit. What no choice of unit can fix is the range of lengths within one scene: the pair
// test squares products of a distance and a velocity difference (length^4 terms), so the ratio of
// the largest length (the box, or the farthest a particle can move in a sub-step) to the contact
// distance s = 2r must stay within kMaxLengthRatio. Separately, the kinetic energy is reported in
// the scene's own units and must fit in a double.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "particle/io.hpp"
#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "particle/scene.hpp"

namespace particle {

// Largest N: indices are 32-bit and the top values mark walls.
inline constexpr std::int64_t kMaxParticles = 100'000'000;

// The header's rules, one per field, as read_scene applies them line by line and psweep to every
// configuration: the problem, or "" when the value is fine.
std::string particle_count_problem(std::int64_t n);  // N in [1, kMaxParticles]
std::string box_problem(double L);                   // L positive
std::string radius_problem(double L, double r);      // r positive, L >= 2r
std::string steps_problem(std::int64_t steps);       // S not negative
// A random scene without a given speed range needs the default one (L/(8r) to L/4) finite.
std::string default_speeds_problem(double L, double r);
// L/(2r) within kMaxLengthRatio (check_representable's first rule).
std::string width_problem(double L, double r);

// What psim would be asked to run: a random scene from its header, seed and speeds, or a scene
// file as read.
struct RunRequest {
  SceneHeader header;
  RunOptions options;
  std::uint64_t seed = RandomInit{}.seed;  // for a random scene
  std::optional<SpeedRange> speed;         // for a random scene; default L/(8r) to L/4
  const Scene* given = nullptr;            // the scene file; none: psim places a random scene
};

// Random scenes of at most this many particles are drawn by run_limit_breach where the header
// alone cannot decide: 2^18 disks take up to about 0.3 s (2^20: 1.3 s on the shared 2-core
// machine), which psweep pays once per distinct scene.
inline constexpr std::int64_t kMaxDrawnToCheck = std::int64_t{1} << 18;

// The first limit of psim's that the run breaks, if any: the header's rules, the options'
// (option_breach), L/(2r), and for random scenes a finite default speed range, room for N disks
// and speeds check_representable accepts. For a random scene psim's outcome is decided by the
// seed: Oler's packing bound refuses what no placement can hold, a union bound accepts what
// psim's placement cannot fail to place, the speed range decides the speed and energy limits
// where even its slowest draw breaks them or its fastest cannot; in between, the scene is drawn
// from the seed exactly as psim draws it (place_random, check_representable's rules), up to
// kMaxDrawnToCheck particles (beyond, psim decides when it runs). For the continuous-time engine
// the same goes for its box crossings (kMaxEventCrossings). The keys: "N" for placement,
// "speed_max" (or "r" with the default speeds) for speed, energy and crossings. A scene file's
// particles (`given`) are checked as psim checks them: "slow_factor" for the speed per sub-step,
// "scene_file" for the energy and the box crossings.
std::optional<LimitBreach> run_limit_breach(const RunRequest& run);

// 2^506 (about 2.6e152): with the unit centred between s and the largest length M, the
// length^4 terms of the pair test stay below 4 (M/s)^2 <= 2^1014, under the largest double
// (2^1024) with room for their sums; the smallest (s^2) stays a normal double.
inline constexpr double kMaxLengthRatio = 0x1p506;

// The continuous-time engine (`event`) processes every collision, so a scene whose fastest
// particle crosses the box more often than a computer can count never finishes (speeds near 1e150
// in a box of 1000 make 1e147 wall collisions per time unit), and beyond 2^52 crossings per run
// the event times, doubles up to S, can no longer tell consecutive collisions apart. It refuses a
// run beyond this many box crossings (about 1e12, hours of work).
inline constexpr double kMaxEventCrossings = 0x1p40;

// The continuous-time engine places a particle at x + v (t - epoch), t a rounded double up to S:
// a coordinate near L is off by up to 2^-53 L, and a pair's separation at a rounded event time by
// up to 2^-53 S times their relative speed (at most twice the speed bound V). Where that blur,
// bounded by 2^-52 (L + 2 V S), exceeds this fraction of the contact distance, the engine cannot
// tell contact from overlap, and two centres can round to one point, where a collision has no
// normal (fuzz_scene found NaN so at L = 4e24, r = 1). It refuses such a run.
inline constexpr double kMaxEventBlur = 0x1p-10;

// How many times a particle at the scene's speed bound sqrt(sum v^2) crosses the box (L - 2r) in
// its S time units: a bound on each particle's wall collisions, whatever the engine or slow
// factor (infinite for L = 2r with anything moving). simulate() refuses a continuous-time run
// beyond kMaxEventCrossings; psweep refuses it up front (run_limit_breach).
double box_crossings(const Scene& scene);

// Throws InputError (particle/io.hpp) naming the field and the limit when the scene cannot be
// represented: L/(2r) beyond kMaxLengthRatio ("r"), a speed bound beyond kMaxLengthRatio contact
// distances per sub-step ("speed"), or a kinetic energy beyond the largest double ("energy");
// for a continuous-time `engine`, also its limits (kMaxEventCrossings, a box of L = 2r,
// kMaxEventBlur). `source` prefixes the message (a file name). simulate() calls it; programs call
// it first, so that nothing is written for a run that cannot start.
void check_representable(const Scene& scene, int slow_factor, const std::string& source = "scene",
                         std::string_view engine = {});

// The warning psim prints on stderr (exit status unchanged) when a run's kinetic energy, or its
// drift, is not finite; "" when all three figures are finite. check_representable refuses a
// scene whose energy overflows, so this guards only against rounding at the very edge of the
// range carrying the final energy over.
std::string energy_warning(const Physics& physics);

}  // namespace particle
