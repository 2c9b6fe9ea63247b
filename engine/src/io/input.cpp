// Reading the 2019 text format. Every problem is reported once, here at the boundary, as
// `SOURCE:LINE: FIELD: problem`; the engine behind it assumes a valid scene. The input is read
// in large blocks and parsed in place (io/scene_text.hpp), no further than the header allows.
#include <fmt/format.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "io/scene_text.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/random_scene.hpp"

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

// A particle line `i x y vx vy`: its values, or the first rule of the line alone that it breaks,
// in the order its fields are read. One set of rules for both readers: the sequential one turns a
// problem into its message (ParticleRules::fail), ParallelLines hands the block back to it.
enum class LineProblem { none, fields, i, i_range, x, y, vx, vy, x_box, y_box };
struct ParticleLine {
  std::int64_t i = 0;
  double v[4];  // x, y, vx, vy
};

struct ParticleRules {
  std::int64_t n;
  double lo, hi;  // the box's centre range [r, L-r]

  // The field count and the index, then the values: the sequential reader names a duplicate
  // index between the two.
  LineProblem parse_index(const detail::LineFields& f, ParticleLine& line) const {
    if (f.count() != 5) return LineProblem::fields;
    if (!detail::try_parse_integer(f.field(0), line.i)) return LineProblem::i;
    if (line.i < 0 || line.i >= n) return LineProblem::i_range;
    return LineProblem::none;
  }
  LineProblem parse_values(const detail::LineFields& f, ParticleLine& line) const {
    for (int k = 0; k < 4; ++k)
      if (!detail::try_parse_real(f.field(k + 1), line.v[k]))
        return static_cast<LineProblem>(static_cast<int>(LineProblem::x) + k);
    if (line.v[0] < lo || line.v[0] > hi) return LineProblem::x_box;
    if (line.v[1] < lo || line.v[1] > hi) return LineProblem::y_box;
    return LineProblem::none;
  }

  // The message of the current line's problem.
  [[noreturn]] void fail(const LineReader& r, LineProblem problem, const ParticleLine& line) const {
    static constexpr const char* kNames[] = {"x", "y", "vx", "vy"};
    switch (problem) {
      case LineProblem::fields:
        r.fail("particle", fmt::format("expected 5 fields `i x y vx vy`, got {}", r.count()));
      case LineProblem::i:
        detail::bad_integer(r, "i", r.field(0));
      case LineProblem::i_range:
        r.fail("i", fmt::format("index {} out of range [0, {}]", line.i, n - 1));
      case LineProblem::x_box:
      case LineProblem::y_box: {
        const int k = problem == LineProblem::x_box ? 0 : 1;
        r.fail(kNames[k], fmt::format("{} is outside [r, L-r] = [{}, {}]", line.v[k], lo, hi));
      }
      case LineProblem::x:
      case LineProblem::y:
      case LineProblem::vx:
      case LineProblem::vy: {
        const int k = static_cast<int>(problem) - static_cast<int>(LineProblem::x);
        detail::bad_real(r, kNames[k], r.field(k + 1));
      }
      case LineProblem::none:
        break;
    }
    throw std::logic_error("ParticleRules::fail without a problem");
  }
};

// Below these, threads cost more than they save.
constexpr std::int64_t kParallelParticles = 16384;
constexpr std::size_t kParallelBytes = std::size_t{64} << 10;

// Reads a block of whole particle lines on `threads` threads, each a range of its lines, with the
// rules of read_particles below but without its messages: false at anything it would reject, with
// the scene and `seen` as before, so that it reads the block again and names the first problem.
// Each thread parses its range into a list of its own; the indices are then marked seen in line
// order by one thread (a duplicate across ranges is found as on one thread), and only then does
// each thread store its values, every index written by one thread.
class ParallelLines {
 public:
  ParallelLines(Particles& p, const ParticleRules& rules, std::vector<std::uint8_t>& seen,
                int threads)
      : p_(p), rules_(rules), seen_(seen), threads_(threads), parts_(threads) {}

  // On success, adds the block's lines and particle lines to `lines` and `given`.
  bool read(std::string_view block, std::int64_t& lines, std::int64_t& given) {
    for (Part& part : parts_) part.clear();  // a team may have fewer threads than asked
    bool ok = true;
#pragma omp parallel num_threads(threads_)
    {
      const int t = omp_get_thread_num(), count = omp_get_num_threads();
      parts_[t].ok =
          read_range(range_start(block, t, count), range_start(block, t + 1, count), parts_[t]);
#pragma omp barrier
#pragma omp single
      ok = mark_seen();
      if (ok) store(parts_[t]);
    }
    if (!ok) return false;
    for (const Part& part : parts_) {
      lines += part.lines;
      given += static_cast<std::int64_t>(part.index.size());
    }
    return true;
  }

 private:
  struct alignas(64) Part {  // a cache line of its own: each thread updates its part per line
    std::vector<std::uint32_t> index;
    std::vector<double> values;  // x, y, vx, vy of each line in `index`
    std::int64_t lines = 0;
    bool ok = true;
    void clear() {
      index.clear();
      values.clear();
      lines = 0;
      ok = true;
    }
  };

  // Range t of `count` starts at the line after the t-th fraction of the block.
  static const char* range_start(std::string_view block, int t, int count) {
    if (t == 0) return block.data();
    if (t == count) return block.data() + block.size();
    const std::size_t from = block.size() * static_cast<std::size_t>(t) / count;
    return static_cast<const char*>(std::memchr(block.data() + from, '\n', block.size() - from)) +
           1;
  }

  // The whole lines [at, end) into `part`.
  bool read_range(const char* at, const char* end, Part& part) const {
    detail::LineFields f;
    ParticleLine line;
    for (const char* newline; at < end; at = newline + 1, ++part.lines) {
      newline = static_cast<const char*>(std::memchr(at, '\n', end - at));
      if (newline - at >= static_cast<std::ptrdiff_t>(kMaxLineBytes)) return false;
      f.split(at, newline);
      if (f.count() == 0) continue;
      if (rules_.parse_index(f, line) != LineProblem::none ||
          rules_.parse_values(f, line) != LineProblem::none)
        return false;
      part.index.push_back(static_cast<std::uint32_t>(line.i));
      part.values.insert(part.values.end(), line.v, line.v + 4);
    }
    return true;
  }

  // Marks every part's indices seen, in line order; false (and none marked) when a part failed or
  // an index was seen before.
  bool mark_seen() {
    std::size_t marked = 0;
    for (const Part& part : parts_) {
      if (!part.ok) return unmark(marked);
      for (const std::uint32_t i : part.index) {
        if (seen_[i]) return unmark(marked);
        seen_[i] = 1;
        ++marked;
      }
    }
    return true;
  }

  // Undoes the first `marked` marks of mark_seen().
  bool unmark(std::size_t marked) {
    for (const Part& part : parts_)
      for (const std::uint32_t i : part.index) {
        if (marked-- == 0) return false;
        seen_[i] = 0;
      }
    return false;
  }

  void store(const Part& part) {
    const double* v = part.values.data();
    for (const std::uint32_t i : part.index) {
      p_.x[i] = v[0];
      p_.y[i] = v[1];
      p_.vx[i] = v[2];
      p_.vy[i] = v[3];
      v += 4;
    }
  }

  Particles& p_;
  const ParticleRules& rules_;
  std::vector<std::uint8_t>& seen_;
  int threads_;
  std::vector<Part> parts_;
};

// The particle lines `i x y vx vy`, in any order, blank lines allowed; returns how many. Large
// scenes on several threads read the buffer's whole lines by ParallelLines until it finds a
// problem; from there on line by line, which names it.
std::int64_t read_particles(LineReader& r, Scene& scene, std::int64_t n,
                            std::vector<std::uint8_t>& seen, int threads) {
  Particles& p = scene.particles;
  std::int64_t given = 0;
  const ParticleRules rules{n, scene.r, scene.L - scene.r};
  if (threads > 1 && n >= kParallelParticles) {
    ParallelLines parallel(p, rules, seen, threads);
    for (std::string_view block; (block = r.whole_lines()).size() >= kParallelBytes;) {
      std::int64_t lines = 0;
      if (!parallel.read(block, lines, given)) break;
      r.skip(block, lines);
    }
  }
  while (r.next()) {
    if (r.count() == 0) continue;
    if (given == n)
      r.fail("particle", fmt::format("extra line: all {} particles are already given", n));
    ParticleLine line;
    if (const LineProblem problem = rules.parse_index(r.fields(), line);
        problem != LineProblem::none)
      rules.fail(r, problem, line);
    if (seen[line.i]) r.fail("i", fmt::format("duplicate index {}", line.i));
    if (const LineProblem problem = rules.parse_values(r.fields(), line);
        problem != LineProblem::none)
      rules.fail(r, problem, line);
    seen[line.i] = 1;
    p.x[line.i] = line.v[0];
    p.y[line.i] = line.v[1];
    p.vx[line.i] = line.v[2];
    p.vy[line.i] = line.v[3];
    ++given;
  }
  return given;
}

}  // namespace

SceneHeader read_scene_header(std::istream& in, const std::string& source) {
  LineReader r(in, source);
  return read_header(r);
}

Scene read_scene(std::istream& in, const std::string& source, const RandomInit& init, int threads) {
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
  threads = resolve_threads(threads);
  const std::int64_t given = read_particles(r, scene, n, seen, threads);
  if (given == 0) {
    if (const std::string problem = default_speeds_problem(scene.L, scene.r);
        !init.speed && !problem.empty())
      throw InputError(source + ":3: r: " + problem);
    try {
      place_random(scene, init, threads);
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
