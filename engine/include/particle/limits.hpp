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
#include "particle/scene.hpp"

namespace particle {

// 2^506 (about 2.6e152): with the unit centred between s and the largest length M, the
// length^4 terms of the pair test stay below 4 (M/s)^2 <= 2^1014, under the largest double
// (2^1024) with room for their sums; the smallest (s^2) stays a normal double.
inline constexpr double kMaxLengthRatio = 0x1p506;

// Throws InputError (particle/io.hpp) naming the field and the limit when the scene cannot be
// represented: L/(2r) beyond kMaxLengthRatio ("r"), a speed bound beyond kMaxLengthRatio contact
// distances per sub-step ("speed"), or a kinetic energy beyond the largest double ("energy").
// `source` prefixes the message (a file name). simulate() calls it; programs may call it first.
void check_representable(const Scene& scene, int slow_factor, const std::string& source = "scene");

}  // namespace particle
