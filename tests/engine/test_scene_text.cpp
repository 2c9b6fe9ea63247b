// The parser's fast decimal path gives the very double std::from_chars gives, or declines.
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <random>
#include <string>
#include <vector>

#include "io/scene_text.hpp"

namespace particle::detail {
namespace {

double from_chars_value(const std::string& token) {
  double value = 0;
  const char* at = token.data() + (token[0] == '+');
  std::from_chars(at, token.data() + token.size(), value);
  return value;
}

// Bit for bit (so -0.0 differs from 0.0); true when the fast path took the token.
bool fast_matches(const std::string& token, bool& taken) {
  double fast = 0;
  taken = parse_plain_decimal(token, fast);
  return !taken || std::bit_cast<std::uint64_t>(fast) ==
                       std::bit_cast<std::uint64_t>(from_chars_value(token));
}

TEST(SceneText, PlainDecimalsMatchFromCharsOrDecline) {
  struct Case {
    const char* token;
    bool taken;
  };
  for (const Case c : {Case{"0", true},
                       {"-0", true},
                       {"+0.5", true},
                       {".5", true},
                       {"5.", true},
                       {"-1401.93207880", true},
                       {"0.1234567890123456", true},  // eight decimals twice
                       {"0.123456789012345", true},   // eight at once, then seven one by one
                       {"3.1234567/", false},         // '/' and ':' border the digits
                       {"3.12345:78", false},
                       {"3.1234567a9", false},
                       {"3.99999999", true},
                       {"0.1", true},
                       {"9007199254740992", true},
                       {"9007199254740993", false},
                       {"0.000000000000000001", true},
                       {"0.0000000000000000000001", false},
                       {"1234567890123456789", false},
                       {"1e5", false},
                       {"-", false},
                       {".", false},
                       {"+-1", false},
                       {"1.5.3", false},
                       {"12a", false},
                       {"", false}}) {
    bool taken = false;
    EXPECT_TRUE(fast_matches(c.token, taken)) << c.token;
    EXPECT_EQ(taken, c.taken) << c.token;
  }
  // Random fields as psim prints them (%.8f) and with other numbers of digits.
  std::mt19937_64 rng(2019);
  std::uniform_int_distribution<int> width(1, 19);
  int bad = 0;
  for (int k = 0; k < 200000 && bad < 10; ++k) {
    std::string token = rng() % 2 ? "-" : "";
    const int digits = width(rng), point = static_cast<int>(rng() % (digits + 1));
    for (int d = 0; d < digits; ++d) {
      if (d == point) token += '.';
      token += static_cast<char>('0' + rng() % 10);
    }
    bool taken = false;
    if (!fast_matches(token, taken)) {
      ++bad;
      ADD_FAILURE() << token;
    }
  }
  EXPECT_EQ(bad, 0);
}

// The fields of a line by the rules alone (scene_text.hpp): runs of spaces and tabs separate them,
// trailing blanks and '\r' are dropped.
std::vector<std::string> fields_by_rule(std::string line) {
  while (!line.empty() && (line.back() == ' ' || line.back() == '\t' || line.back() == '\r'))
    line.pop_back();
  std::vector<std::string> fields;
  std::string field;
  for (const char c : line + ' ') {
    if (c != ' ' && c != '\t') {
      field += c;
    } else if (!field.empty()) {
      fields.push_back(field);
      field.clear();
    }
  }
  return fields;
}

// Lines of every length up to past the mask's reach (LineFields::kReadAhead), fields crossing
// its 32- and 64-byte words, leading blanks, tabs, '\r' and more fields than are kept: split()
// gives the rule's fields. The bytes after the line are not blanks, so a mask that read past its
// end would show.
TEST(SceneText, LineFieldsSplitAsTheRulesSayAtEveryLength) {
  std::mt19937_64 rng(56);
  int bad = 0;
  for (std::size_t length = 0; length <= LineFields::kReadAhead + 8 && bad < 10; ++length)
    for (int k = 0; k < 200 && bad < 10; ++k) {
      std::string line;
      for (std::size_t b = 0; b < length; ++b) {
        const auto pick = rng() % 10;
        line += pick < 2                       ? ' '
                : pick == 2                    ? '\t'
                : pick == 3 && b + 1 == length ? '\r'
                                               : static_cast<char>('0' + pick);
      }
      std::string buffer = line + std::string(LineFields::kReadAhead, 'x');
      LineFields f;
      f.split(buffer.data(), buffer.data() + length);
      const std::vector<std::string> want = fields_by_rule(line);
      const auto kept = std::min<std::size_t>(want.size(), LineFields::kMaxFields);
      bool same = f.count() == static_cast<int>(want.size());
      for (std::size_t i = 0; same && i < kept; ++i) same = f.field(static_cast<int>(i)) == want[i];
      if (!same) {
        ++bad;
        ADD_FAILURE() << "`" << line << "`";
      }
    }
  EXPECT_EQ(bad, 0);
}

}  // namespace
}  // namespace particle::detail
