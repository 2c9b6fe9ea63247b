// Reading the 2019 text format. Every problem is reported once, here at the boundary, as
// `SOURCE:LINE: FIELD: problem`; the engine behind it assumes a valid scene.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <string_view>
#include <vector>

#include "particle/io.hpp"
#include "particle/random_scene.hpp"

namespace particle {
namespace {

// Largest N we accept: indices are 32-bit and the top values mark walls.
constexpr std::int64_t kMaxParticles = 100'000'000;

class LineReader {
 public:
  LineReader(std::istream& in, std::string source) : in_(in), source_(std::move(source)) {}

  // Next line split into tokens; false at end of input.
  bool next(std::vector<std::string_view>& tokens) {
    if (!std::getline(in_, line_)) return false;
    ++number_;
    tokens.clear();
    std::string_view rest(line_);
    while (true) {
      const auto start = rest.find_first_not_of(" \t\r");
      if (start == std::string_view::npos) break;
      rest.remove_prefix(start);
      const auto end = rest.find_first_of(" \t\r");
      tokens.push_back(rest.substr(0, end));
      if (end == std::string_view::npos) break;
      rest.remove_prefix(end);
    }
    return true;
  }

  [[noreturn]] void fail(std::string_view field, const std::string& problem) const {
    throw InputError(source_ + ":" + std::to_string(number_) + ": " + std::string(field) + ": " +
                     problem);
  }
  [[noreturn]] void fail_at_end(std::string_view field, const std::string& problem) const {
    throw InputError(source_ + ":" + std::to_string(number_ + 1) + ": " + std::string(field) +
                     ": " + problem);
  }

 private:
  std::istream& in_;
  std::string source_;
  std::string line_;
  std::int64_t number_ = 0;
};

std::string quoted(std::string_view token) { return fmt::format("\"{}\"", token); }

std::int64_t parse_integer(const LineReader& r, std::string_view field, std::string_view token) {
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec == std::errc::result_out_of_range) r.fail(field, "integer out of range: " + quoted(token));
  if (ec != std::errc() || end != token.data() + token.size())
    r.fail(field, "expected an integer, got " + quoted(token));
  return value;
}

double parse_real(const LineReader& r, std::string_view field, std::string_view token) {
  double value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size())
    r.fail(field, "expected a number, got " + quoted(token));
  if (!std::isfinite(value)) r.fail(field, "expected a finite number, got " + quoted(token));
  return value;
}

// One header line holding exactly one token.
std::string_view header_token(LineReader& r, std::vector<std::string_view>& tokens,
                              std::string_view field, std::string_view what) {
  if (!r.next(tokens)) r.fail_at_end(field, "missing (expected " + std::string(what) + ")");
  if (tokens.size() != 1)
    r.fail(field,
           "expected one value (" + std::string(what) + "), got " + std::to_string(tokens.size()));
  return tokens[0];
}

}  // namespace

Scene read_scene(std::istream& in, const std::string& source, const RandomInit& init) {
  LineReader r(in, source);
  std::vector<std::string_view> t;
  Scene scene;

  const std::int64_t n = parse_integer(r, "N", header_token(r, t, "N", "the number of particles"));
  if (n < 1 || n > kMaxParticles)
    r.fail("N",
           "must be between 1 and " + std::to_string(kMaxParticles) + ", got " + std::to_string(n));
  scene.L = parse_real(r, "L", header_token(r, t, "L", "the box size"));
  if (!(scene.L > 0)) r.fail("L", "must be positive");
  scene.r = parse_real(r, "r", header_token(r, t, "r", "the particle radius"));
  if (!(scene.r > 0)) r.fail("r", "must be positive");
  if (scene.L < 2 * scene.r)
    r.fail("r", "a particle of this radius does not fit in the box (L < 2r)");
  scene.steps = parse_integer(r, "S", header_token(r, t, "S", "the number of steps"));
  if (scene.steps < 0) r.fail("S", "must not be negative");
  const std::string_view mode = header_token(r, t, "mode", "print or perf");
  if (mode == "print")
    scene.mode = OutputMode::print;
  else if (mode == "perf")
    scene.mode = OutputMode::perf;
  else
    r.fail("mode", "expected print or perf, got " + quoted(mode));

  scene.particles = Particles(static_cast<std::size_t>(n));
  Particles& p = scene.particles;
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(n), 0);
  std::int64_t given = 0;
  const double lo = scene.r, hi = scene.L - scene.r;
  while (r.next(t)) {
    if (t.empty()) continue;
    if (given == n)
      r.fail("particle", "extra line: all " + std::to_string(n) + " particles are already given");
    if (t.size() != 5)
      r.fail("particle", "expected 5 fields `i x y vx vy`, got " + std::to_string(t.size()));
    const std::int64_t i = parse_integer(r, "i", t[0]);
    if (i < 0 || i >= n)
      r.fail("i",
             "index " + std::to_string(i) + " out of range [0, " + std::to_string(n - 1) + "]");
    if (seen[i]) r.fail("i", "duplicate index " + std::to_string(i));
    seen[i] = 1;
    p.x[i] = parse_real(r, "x", t[1]);
    p.y[i] = parse_real(r, "y", t[2]);
    p.vx[i] = parse_real(r, "vx", t[3]);
    p.vy[i] = parse_real(r, "vy", t[4]);
    if (p.x[i] < lo || p.x[i] > hi) r.fail("x", "particle outside [r, L-r]");
    if (p.y[i] < lo || p.y[i] > hi) r.fail("y", "particle outside [r, L-r]");
    ++given;
  }
  if (given == 0) {
    if (!init.speed && !std::isfinite(default_speed_range(scene.L, scene.r).max))
      throw InputError(source +
                       ":3: r: the default speed range L/(8r) to L/4 is not finite; "
                       "give a speed range");
    try {
      place_random(scene, init);
    } catch (const InputError& e) {
      throw InputError(source + ":1: N: " + e.what());
    }
  } else if (given < n) {
    std::int64_t missing = 0;
    while (seen[missing]) ++missing;
    r.fail_at_end("particle", "expected " + std::to_string(n) + " particle lines, got " +
                                  std::to_string(given) + " (index " + std::to_string(missing) +
                                  " is missing)");
  }
  return scene;
}

}  // namespace particle
