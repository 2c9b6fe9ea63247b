// Reading the 2019 text format. Every problem is reported once, here at the boundary, as
// `SOURCE:LINE: FIELD: problem`; the engine behind it assumes a valid scene. The whole input is
// read into one buffer and parsed in place (scene_text.hpp): the particle lines of the
// 1M-particle scene take about as long as reading the file.
#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "particle/io.hpp"
#include "particle/random_scene.hpp"
#include "scene_text.hpp"

namespace particle {
namespace {

using detail::LineReader;
using detail::parse_integer;
using detail::parse_real;
using detail::quoted;

// Largest N we accept: indices are 32-bit and the top values mark walls.
constexpr std::int64_t kMaxParticles = 100'000'000;

// One header line holding exactly one token.
std::string_view header_token(LineReader& r, std::string_view field, std::string_view what) {
  if (!r.next()) r.fail_at_end(field, fmt::format("missing (expected {})", what));
  if (r.count() != 1)
    r.fail(field, fmt::format("expected one value ({}), got {}", what, r.count()));
  return r.field(0);
}

// The five header lines N, L, r, S, mode; returns N.
std::int64_t read_header(LineReader& r, Scene& scene) {
  const std::int64_t n = parse_integer(r, "N", header_token(r, "N", "the number of particles"));
  if (n < 1 || n > kMaxParticles)
    r.fail("N", fmt::format("must be between 1 and {}, got {}", kMaxParticles, n));
  scene.L = parse_real(r, "L", header_token(r, "L", "the box size"));
  if (!(scene.L > 0)) r.fail("L", "must be positive");
  scene.r = parse_real(r, "r", header_token(r, "r", "the particle radius"));
  if (!(scene.r > 0)) r.fail("r", "must be positive");
  if (scene.L < 2 * scene.r)
    r.fail("r", "a particle of this radius does not fit in the box (L < 2r)");
  scene.steps = parse_integer(r, "S", header_token(r, "S", "the number of steps"));
  if (scene.steps < 0) r.fail("S", "must not be negative");
  const std::string_view mode = header_token(r, "mode", "print or perf");
  if (mode == "print")
    scene.mode = OutputMode::print;
  else if (mode == "perf")
    scene.mode = OutputMode::perf;
  else
    r.fail("mode", "expected print or perf, got " + quoted(mode));
  return n;
}

[[noreturn]] void outside_box(const LineReader& r, std::string_view field, double value, double lo,
                              double hi) {
  r.fail(field, fmt::format("{} is outside [r, L-r] = [{}, {}]", value, lo, hi));
}

// The particle lines `i x y vx vy`, in any order, blank lines allowed; returns how many.
std::int64_t read_particles(LineReader& r, Scene& scene, std::int64_t n,
                            std::vector<std::uint8_t>& seen) {
  Particles& p = scene.particles;
  std::int64_t given = 0;
  const double lo = scene.r, hi = scene.L - scene.r;
  while (r.next()) {
    if (r.count() == 0) continue;
    if (given == n)
      r.fail("particle", fmt::format("extra line: all {} particles are already given", n));
    if (r.count() != 5)
      r.fail("particle", fmt::format("expected 5 fields `i x y vx vy`, got {}", r.count()));
    const std::int64_t i = parse_integer(r, "i", r.field(0));
    if (i < 0 || i >= n) r.fail("i", fmt::format("index {} out of range [0, {}]", i, n - 1));
    if (seen[i]) r.fail("i", fmt::format("duplicate index {}", i));
    seen[i] = 1;
    p.x[i] = parse_real(r, "x", r.field(1));
    p.y[i] = parse_real(r, "y", r.field(2));
    p.vx[i] = parse_real(r, "vx", r.field(3));
    p.vy[i] = parse_real(r, "vy", r.field(4));
    if (p.x[i] < lo || p.x[i] > hi) outside_box(r, "x", p.x[i], lo, hi);
    if (p.y[i] < lo || p.y[i] > hi) outside_box(r, "y", p.y[i], lo, hi);
    ++given;
  }
  return given;
}

}  // namespace

Scene read_scene(std::istream& in, const std::string& source, const RandomInit& init) {
  const detail::InputText text(in);
  LineReader r(text.view(), source);
  Scene scene;
  const std::int64_t n = read_header(r, scene);

  scene.particles = Particles(static_cast<std::size_t>(n));
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(n), 0);
  const std::int64_t given = read_particles(r, scene, n, seen);
  if (given == 0) {
    if (!init.speed && !std::isfinite(default_speed_range(scene.L, scene.r).max))
      throw InputError(source +
                       ":3: r: the default speed range L/(8r) to L/4 is not finite; "
                       "give a speed range");
    try {
      place_random(scene, init);
      scene.generated = true;
    } catch (const InputError& e) {
      throw InputError(source + ":1: N: " + e.what());
    }
  } else if (given < n) {
    std::int64_t missing = 0;
    while (seen[missing]) ++missing;
    r.fail_at_end(
        "particle",
        fmt::format("expected {} particle lines, got {} (index {} is missing)", n, given, missing));
  }
  return scene;
}

}  // namespace particle
