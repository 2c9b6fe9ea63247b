// Every bad input of docs/psim.md, "Bad input", is an InputError naming the line and the field.
#include <gtest/gtest.h>

#include <cstdio>
#include <istream>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "helpers.hpp"

namespace particle {
namespace {

using testing::scene_from_text;

// Expects an InputError whose message contains `test:LINE: FIELD:` and `detail`.
void expect_error(const std::string& text, int line, const std::string& field,
                  const std::string& detail) {
  try {
    scene_from_text(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test:" + std::to_string(line) + ": " + field + ":"), std::string::npos)
        << what;
    EXPECT_NE(what.find(detail), std::string::npos) << what;
  }
}

const std::string kHeader = "2\n100\n1\n10\nperf\n";

TEST(Input, ReadsExplicitParticlesInAnyOrder) {
  const Scene s = scene_from_text(kHeader + "1 10 20 -1 2\n0 30 40 3.5 -4e-1\n\n");
  EXPECT_EQ(s.size(), 2u);
  EXPECT_EQ(s.L, 100);
  EXPECT_EQ(s.steps, 10);
  EXPECT_EQ(s.mode, OutputMode::perf);
  EXPECT_EQ(s.particles.x[0], 30);
  EXPECT_EQ(s.particles.vy[0], -0.4);
  EXPECT_EQ(s.particles.y[1], 20);
}

TEST(Input, HeaderErrors) {
  expect_error("abc\n", 1, "N", "expected an integer");
  expect_error("0\n100\n1\n1\nperf\n", 1, "N", "between 1 and");
  expect_error("-3\n", 1, "N", "between 1 and");
  expect_error("2\n", 2, "L", "missing");
  expect_error("2\nnan\n", 2, "L", "finite");
  expect_error("2\ninf\n", 2, "L", "finite");
  expect_error("2\n-5\n1\n1\nperf\n", 2, "L", "positive");
  expect_error("2\n100\n0\n1\nperf\n", 3, "r", "positive");
  expect_error("2\n100\n1x\n1\nperf\n", 3, "r", "expected a number");
  expect_error("2\n1\n1\n1\nperf\n", 3, "r", "L < 2r");
  expect_error("2\n100\n1\n-1\nperf\n", 4, "S", "negative");
  expect_error("2\n100\n1\n1.5\nperf\n", 4, "S", "integer");
  expect_error("2\n100\n1\n1\nfast\n", 5, "mode", "print or perf");
  expect_error("2\n100 3\n", 2, "L", "one value");
  expect_error("99999999999999999999\n", 1, "N", "out of range");
}

TEST(Input, ParticleLineErrors) {
  expect_error(kHeader + "0 10 20 1\n", 6, "particle", "5 fields");
  expect_error(kHeader + "0 10 20 1 2 3\n", 6, "particle", "5 fields");
  expect_error(kHeader + "0 10 20 1 2\n", 7, "particle", "expected 2 particle lines, got 1");
  expect_error(kHeader + "0 10 20 1 2\n1 30 40 1 1\n2 50 50 0 0\n", 8, "particle", "extra line");
  expect_error(kHeader + "0 10 20 1 2\n0 30 40 1 1\n", 7, "i", "duplicate index 0");
  expect_error(kHeader + "2 10 20 1 2\n", 6, "i", "out of range");
  expect_error(kHeader + "-1 10 20 1 2\n", 6, "i", "out of range");
  expect_error(kHeader + "0 0.5 20 1 2\n", 6, "x", "outside [r, L-r]");
  expect_error(kHeader + "0 10 99.5 1 2\n", 6, "y", "outside [r, L-r]");
  expect_error(kHeader + "0 10 20 nan 2\n", 6, "vx", "finite");
  expect_error(kHeader + "0 10 20 1 two\n", 6, "vy", "expected a number");
}

// A scene large enough for the particle lines to be parsed on several threads (ParallelLines in
// io/input.cpp): lines in a scrambled index order, blank lines among them.
std::vector<std::string> large_scene_lines(int n) {
  std::vector<std::string> lines = {std::to_string(n), "100000", "1", "10", "perf"};
  for (int k = 0; k < n; ++k) {
    const int i = static_cast<int>((static_cast<std::int64_t>(k) * 7919) % n);
    char line[96];
    std::snprintf(line, sizeof line, "%d %.8f %.8f %.8f %.8f", i, 10 + 9.25 * (i % 9973),
                  99990 - 2.25 * k, 0.5 - 1e-3 * (k % 1000), (k % 7) * -0.0625);
    lines.push_back(line);
    if (k % 5000 == 17) lines.push_back(k % 2 ? "" : " \t ");
  }
  return lines;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// The error message reading `text` on `threads` threads, or "" when it reads.
std::string error_on(const std::string& text, int threads) {
  try {
    std::istringstream in(text);
    read_scene(in, "test", {}, threads);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Input, ParallelParsingGivesTheSameSceneAndMessages) {
  const int n = 40000;  // ~2 MB: two blocks of the reader's buffer
  const std::vector<std::string> lines = large_scene_lines(n);
  std::istringstream one(joined(lines));
  const std::uint64_t hash = state_hash(read_scene(one, "test", {}, 1).particles);
  for (const int threads : {2, 3, 4}) {
    std::istringstream in(joined(lines));
    EXPECT_EQ(state_hash(read_scene(in, "test", {}, threads).particles), hash) << threads;
  }
  // Each problem at lines in different ranges and blocks: the first line, near a third and a
  // half of the first block, the second block, the last line.
  const std::size_t at_lines[] = {5, 5000, 9000, 30000, lines.size() - 1};
  const auto replaced = [&](std::size_t at, const std::string& line) {
    std::vector<std::string> changed = lines;
    changed[at] = line;
    return joined(changed);
  };
  for (const std::size_t at : at_lines) {
    const std::string earlier_index = lines[at == 5 ? lines.size() - 1 : 5].substr(
        0, lines[at == 5 ? lines.size() - 1 : 5].find(' '));
    for (const std::string& bad :
         {earlier_index + " 10 20 1 2", std::string("0 10 20 1"), std::string("0 10 20 1 2 3"),
          std::string("0 10 20 1e999 2"), std::string("0 0.5 20 1 2"), std::string("0 10 20 1 x"),
          std::to_string(n) + " 10 20 1 2", "0 10 20 1 2" + std::string(5000, ' ')}) {
      const std::string text = replaced(at, bad);
      const std::string expected = error_on(text, 1);
      EXPECT_FALSE(expected.empty()) << at << ": " << bad;
      for (const int threads : {2, 3})
        EXPECT_EQ(error_on(text, threads), expected) << at << ": " << bad;
    }
  }
  // A line missing, and one too many.
  std::vector<std::string> fewer = lines;
  fewer.erase(fewer.begin() + 20000);
  std::vector<std::string> more = lines;
  more.push_back("0 10 20 1 2");
  for (const std::string& text : {joined(fewer), joined(more)})
    EXPECT_EQ(error_on(text, 3), error_on(text, 1));
}

// The syntax the README promises: CRLF or LF, blank lines, spaces and tabs around and between
// fields, explicit '+' signs, exponents, a last line without a newline.
TEST(Input, AcceptsCrlfBlankLinesTabsAndSigns) {
  const Scene s = scene_from_text(
      " 2 \r\n\t100\r\n+1\r\n10\t\r\nperf\r\n\r\n  \t\r\n1\t10 +20 -1e0  +2.5E-1\r\n\n"
      "+0 30.0 40. .5 -0\t ");
  EXPECT_EQ(s.size(), 2u);
  EXPECT_EQ(s.r, 1);
  EXPECT_EQ(s.particles.y[1], 20);
  EXPECT_EQ(s.particles.vx[1], -1);
  EXPECT_EQ(s.particles.vy[1], 0.25);
  EXPECT_EQ(s.particles.x[0], 30);
  EXPECT_EQ(s.particles.vx[0], 0.5);
}

// Lines of 63, 64 and 65 bytes before the line end (the blank mask covers 64), padded with
// blanks and tabs before, between and after the fields, or by digits up to the last byte; and a
// sixth field at the last byte: the same fields as the plain byte loop finds.
TEST(Input, LinesAroundSixtyFourBytesSplitAlike) {
  const std::string header = "1\n100\n1\n0\nperf\n";
  for (const std::size_t length : {63u, 64u, 65u}) {
    const std::string fields = "0 10 20 1 2";
    const std::string pad(length - fields.size(), ' ');
    for (const std::string& line :
         {pad + fields, fields + pad, "0\t" + pad + "10 20 1 2", "0 10 20 1 " + pad + "2"}) {
      ASSERT_EQ(line.size(), length);
      const Scene s = scene_from_text(header + line + "\n");
      EXPECT_EQ(s.particles.x[0], 10) << length << ": " << line;
      EXPECT_EQ(s.particles.vy[0], 2) << length << ": " << line;
    }
    const std::string digits = "0 10 20 1 2." + std::string(length - 12, '5');
    EXPECT_EQ(scene_from_text(header + digits).particles.vy[0], 23.0 / 9) << length;
    const std::string six = "0 10 20 1 2" + std::string(length - 12, ' ') + "7";
    ASSERT_EQ(six.size(), length);
    expect_error(header + six + "\n", 6, "particle", "got 6");
  }
}

std::string error_of(const std::string& text) {
  try {
    scene_from_text(text);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

TEST(Input, LongTokensAreCutWithAnEllipsis) {
  const std::string what = error_of(kHeader + "0 10 " + std::string(4000, '7') + " 1 2\n");
  EXPECT_NE(what.find("test:6: y: \"7777777777"), std::string::npos) << what;
  EXPECT_NE(what.find("7\"... (4000 bytes)"), std::string::npos) << what;
  EXPECT_NE(what.find("overflows"), std::string::npos) << what;
  EXPECT_LT(what.size(), 200u) << what;
  expect_error(kHeader + "0 10 20 1 " + std::string(300, 'z') + "\n", 6, "vy", "... (300 bytes)");
}

// A line may hold kMaxLineBytes bytes, its line end included: 4095 before the newline pass (the
// field is then read), 4096 are refused naming the line, also without any newline.
TEST(Input, ALineLongerThanTheLimitIsRefused) {
  const std::string fits = "0 10 20 1 2" + std::string(kMaxLineBytes - 1 - 11, ' ') + "\n";
  ASSERT_EQ(fits.size(), kMaxLineBytes);
  EXPECT_EQ(scene_from_text("1\n100\n1\n10\nperf\n" + fits).particles.vy[0], 2);
  expect_error(kHeader + "0 10 20 1 2 " + std::string(kMaxLineBytes - 12, ' ') + "\n", 6, "line",
               "longer than 4096 bytes");
  expect_error(std::string(100000, '7'), 1, "line", "longer than 4096 bytes");
  expect_error("2\n100\n" + std::string(5000, '\0'), 3, "line", "longer than 4096 bytes");
}

// The input ends within (N + 5) x 4096 bytes, blank lines included: what the header allows.
TEST(Input, TheInputMayNotGoOnBeyondWhatTheHeaderAllows) {
  const std::string particles = "0 10 20 1 2\n1 30 40 1 2\n";
  const std::size_t room = 7 * kMaxLineBytes - kHeader.size() - particles.size();
  EXPECT_EQ(scene_from_text(kHeader + particles + std::string(room, '\n')).size(), 2u);
  expect_error(kHeader + particles + std::string(room + 1, '\n'), 5 + 2 + room + 1, "input",
               "goes on beyond 28672 bytes, the most the header allows (7 lines");
  // a random scene: the header alone, then blank lines
  expect_error("3\n100\n1\n10\nperf\n" + std::string(100000, '\n'), 5 + (32768 - 16) + 1, "input",
               "goes on beyond 32768 bytes");
}

// An input that never ends (a device, a pipe) is read only as far as the header allows.
class Endless : public std::streambuf {
 public:
  explicit Endless(std::string head, char fill) : head_(std::move(head)), fill_(fill) {}
  std::size_t served = 0;

 protected:
  int_type underflow() override {
    // Gives up after 256 MiB, so that a reader without bounds fails this test instead of
    // exhausting memory.
    if (served >= (std::size_t{1} << 28)) return traits_type::eof();
    block_.assign(1 << 16, fill_);
    if (served < head_.size()) block_ = head_.substr(served) + block_;
    served += block_.size();
    setg(block_.data(), block_.data(), block_.data() + block_.size());
    return traits_type::to_int_type(block_[0]);
  }

 private:
  std::string head_, block_;
  char fill_;
};

TEST(Input, AnEndlessInputIsReadOnlyAsFarAsTheHeaderAllows) {
  Endless zeros("", '\0');
  std::istream zeros_in(&zeros);
  EXPECT_THROW(read_scene(zeros_in, "zero", {}), InputError);
  EXPECT_LE(zeros.served, std::size_t{2} << 20);
  Endless blank("3\n100\n1\n10\nperf\n", '\n');
  std::istream blank_in(&blank);
  try {
    read_scene(blank_in, "blank", {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("input: goes on beyond 32768 bytes"), std::string::npos)
        << e.what();
  }
  EXPECT_LE(blank.served, std::size_t{2} << 20);
}

TEST(Input, InvisibleAndControlCharactersAreShownEscaped) {
  expect_error(
      "\xEF\xBB\xBF"
      "2\n100\n1\n10\nperf\n",
      1, "N", "\"\\uFEFF2\"");
  expect_error(
      "\xEF\xBB\xBF"
      "2\n100\n1\n10\nperf\n",
      1, "N", "byte-order mark");
  expect_error(kHeader + "0 10\r20 1 2 3\n", 6, "x", "got \"10\\r20\"");
  expect_error(kHeader + "0 10\x01 20 1 2\n", 6, "x", "got \"10\\x01\"");
  expect_error(kHeader + "0 10 20\xC2\xA0 1 2\n", 6, "y", "got \"20\\u00A0\"");
  expect_error(kHeader + "0 10 20 \xFF 2\n", 6, "vx", "got \"\\xFF\"");
  expect_error(kHeader + "0 10 \"2\\0\" 1 2\n", 6, "y", "got \"\\\"2\\\\0\\\"\"");
  expect_error("2\n100\n1\n10\npe\trf\n", 5, "mode", "one value");
  expect_error("2\n100\n1\n10\nperf\x0B\n", 5, "mode", "got \"perf\\x0B\"");
}

TEST(Input, UnderflowAndOverflowAreNamed) {
  expect_error(kHeader + "0 10 20 1e-400 2\n", 6, "vx", "\"1e-400\" underflows");
  expect_error(kHeader + "0 10 20 1 -2e-324\n", 6, "vy", "underflows");
  expect_error(kHeader + "0 10 20 1e400 2\n", 6, "vx", "\"1e400\" overflows");
  expect_error("2\n1e999\n", 2, "L", "overflows");
  expect_error("2\n100\n1\n99999999999999999999\nperf\n", 4, "S", "out of range");
  expect_error(kHeader + "0 10 20 +-1 2\n", 6, "vx", "expected a number");
  expect_error(kHeader + "+ 10 20 1 2\n", 6, "i", "expected an integer");
}

TEST(Input, OutOfBoxParticlesShowValueAndBounds) {
  expect_error(kHeader + "0 0.5 20 1 2\n", 6, "x", "0.5 is outside [r, L-r] = [1, 99]");
  expect_error(kHeader + "0 10 99.25 1 2\n", 6, "y", "99.25 is outside [r, L-r] = [1, 99]");
}

TEST(Input, TooDenseForRandomPlacementIsAnErrorNotAHang) {
  expect_error("1000\n10\n1\n1\nperf\n", 1, "N", "too dense");
}

TEST(Input, InfiniteDefaultSpeedRangeIsAnError) {
  expect_error("1\n1e300\n1e-300\n1\nperf\n", 3, "r", "not finite");
}

TEST(Output, FormatsLikePrintf) {
  Particles p(3);
  const double values[] = {0.0, -0.0, 1.0 / 3, -2.5e-9, 123456.123456785, 1e15 + 0.5, -7.000000005};
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  std::string expected;
  {
    StateWriter writer(f);
    for (double v : values) {
      p.x.assign(3, v);
      p.y.assign(3, -v);
      p.vx.assign(3, v * 3);
      p.vy.assign(3, v / 7);
      writer.write(4, p);
      for (int i = 0; i < 3; ++i) {
        char line[256];
        std::snprintf(line, sizeof line, "4 %d %.8f %.8f %.8f %.8f\n", i, v, -v, v * 3, v / 7);
        expected += line;
      }
    }
    p.pair_collisions.assign(3, 5);
    p.wall_collisions.assign(3, 6);
    writer.write_final("9", p);
    for (int i = 0; i < 3; ++i) {
      char line[256];
      std::snprintf(line, sizeof line, "9 %d %.8f %.8f %.8f %.8f 5 6\n", i, p.x[i], p.y[i], p.vx[i],
                    p.vy[i]);
      expected += line;
    }
  }
  std::rewind(f);
  std::string actual;
  char buffer[4096];
  std::size_t got;
  while ((got = std::fread(buffer, 1, sizeof buffer, f)) > 0) actual.append(buffer, got);
  std::fclose(f);
  EXPECT_EQ(actual, expected);
}

// What StateWriter writes for `p`; with `in_team`, called as print mode calls it: by one thread
// of a parallel region while the others wait at a barrier (and take its tasks there).
std::string written(int threads, const Particles& p, bool in_team = false) {
  std::FILE* f = std::tmpfile();
  {
    StateWriter writer(f, threads);
#pragma omp parallel num_threads(threads) if (in_team)
    {
#pragma omp master
      {
        writer.write(3, p);
        writer.write_final("-1", p);
      }
#pragma omp barrier
    }
  }
  std::rewind(f);
  std::string text;
  char buffer[1 << 16];
  std::size_t got;
  while ((got = std::fread(buffer, 1, sizeof buffer, f)) > 0) text.append(buffer, got);
  std::fclose(f);
  return text;
}

// Large states are formatted in chunks by several threads: the same bytes as one thread and as
// printf, in order, including lines that take printf's own path (huge values).
TEST(Output, ParallelChunksGiveTheSameBytesAsPrintf) {
  // Two rounds of 12 chunks of 16,384 lines at 3 threads; above the size for which a writer
  // outside a parallel region starts a team of its own (io/output.cpp, kOwnTeamLines).
  const std::size_t n = 200000;
  Particles p(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.x[i] = 1 + i * 0.123456789;
    p.y[i] = i % 997 == 0 ? 1e300 : -static_cast<double>(i) / 512;
    p.vx[i] = i * 1e-9;
    p.vy[i] = -1.0 / (i + 1);
    p.pair_collisions[i] = i;
    p.wall_collisions[i] = 7 * i;
  }
  std::string expected;
  char line[1024];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(line, sizeof line, "3 %zu %.8f %.8f %.8f %.8f\n", i, p.x[i], p.y[i], p.vx[i],
                  p.vy[i]);
    expected += line;
  }
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(line, sizeof line, "-1 %zu %.8f %.8f %.8f %.8f %zu %zu\n", i, p.x[i], p.y[i],
                  p.vx[i], p.vy[i], i, 7 * i);
    expected += line;
  }
  EXPECT_TRUE(written(1, p) == expected);
  EXPECT_TRUE(written(3, p) == expected);
  EXPECT_TRUE(written(3, p, true) == expected);
}

// A state of fewer lines than a round's chunks hold (600 lines, 2 threads: 8 chunks of 128, the
// last three empty) gives the same bytes; the empty chunks are never written (make
// test-sanitize found fwrite given their null data()).
TEST(Output, ChunksPastTheLastLineAreSkipped) {
  Particles p(600);
  for (std::size_t i = 0; i < p.size(); ++i) p.x[i] = 1 + i * 0.5;
  const std::string one = written(1, p);
  EXPECT_EQ(written(2, p), one);
  EXPECT_EQ(written(2, p, true), one);
}

}  // namespace
}  // namespace particle
