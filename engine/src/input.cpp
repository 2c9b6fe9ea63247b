// Reading the 2019 text format. Every problem is reported once, here at the boundary, as
// `SOURCE:LINE: FIELD: problem`; the engine behind it assumes a valid scene. The input is read
// in large blocks and parsed in place (scene_text.hpp), no further than the header allows.
#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/random_scene.hpp"
#include "scene_text.hpp"

namespace particle {
namespace {

using detail::LineReader;
using detail::parse_integer;
using detail::parse_real;
using detail::quoted;

// One header line holding exactly one token.
std::string_view header_token(LineReader& r, std::string_view field, std::string_view what) {
  if (!r.next()) r.fail_at_end(field, fmt::format("missing (expected {})", what));
  if (r.count() != 1)
    r.fail(field, fmt::format("expected one value ({}), got {}", what, r.count()));
  return r.field(0);
}

// Fails at the current line when a rule (particle/limits.hpp) finds a problem.
void check(const LineReader& r, std::string_view field, const std::string& problem) {
  if (!problem.empty()) r.fail(field, problem);
}

// The five header lines N, L, r, S, mode.
constexpr std::int64_t kHeaderLines = 5;
SceneHeader read_header(LineReader& r) {
  SceneHeader h;
  h.n = parse_integer(r, "N", header_token(r, "N", "the number of particles"));
  check(r, "N", particle_count_problem(h.n));
  h.L = parse_real(r, "L", header_token(r, "L", "the box size"));
  check(r, "L", box_problem(h.L));
  h.r = parse_real(r, "r", header_token(r, "r", "the particle radius"));
  check(r, "r", radius_problem(h.L, h.r));
  h.steps = parse_integer(r, "S", header_token(r, "S", "the number of steps"));
  check(r, "S", steps_problem(h.steps));
  const std::string_view mode = header_token(r, "mode", "print or perf");
  if (mode == "print")
    h.mode = OutputMode::print;
  else if (mode == "perf")
    h.mode = OutputMode::perf;
  else
    r.fail("mode", "expected print or perf, got " + quoted(mode));
  return h;
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

SceneHeader read_scene_header(std::istream& in, const std::string& source) {
  LineReader r(in, source);
  return read_header(r);
}

Scene read_scene(std::istream& in, const std::string& source, const RandomInit& init) {
  LineReader r(in, source);
  const SceneHeader header = read_header(r);
  const std::int64_t n = header.n;
  r.limit_lines(kHeaderLines + n);
  Scene scene;
  scene.L = header.L;
  scene.r = header.r;
  scene.steps = header.steps;
  scene.mode = header.mode;

  scene.particles = Particles(static_cast<std::size_t>(n));
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(n), 0);
  const std::int64_t given = read_particles(r, scene, n, seen);
  if (given == 0) {
    if (const std::string problem = default_speeds_problem(scene.L, scene.r);
        !init.speed && !problem.empty())
      throw InputError(source + ":3: r: " + problem);
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
