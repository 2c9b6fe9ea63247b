#include "option_values.hpp"

#include <fmt/format.h>

#include <bit>
#include <charconv>
#include <limits>

#include "particle/io.hpp"
#include "particle/options.hpp"

namespace lab {
namespace {

[[noreturn]] void bad_value(std::string_view option, std::string_view form, std::string_view text) {
  throw particle::InputError(
      fmt::format("{}: expected {}, got {}", option, form, particle::quoted(text)));
}

// The whole token as a decimal integer of type T, with an optional '+' (as in scene files); false
// for anything else, including values beyond T.
template <class T>
bool whole_integer(std::string_view text, T& value) {
  const char* at = text.data();
  const char* end = at + text.size();
  if (text.size() > 1 && at[0] == '+' && at[1] != '-') ++at;  // from_chars takes no '+'
  const auto [stop, ec] = std::from_chars(at, end, value);
  return ec == std::errc() && stop == end;
}

}  // namespace

std::int64_t integer_option(std::string_view option, std::string_view text, std::int64_t lo,
                            std::int64_t hi) {
  std::int64_t value = 0;
  if (!whole_integer(text, value) || value < lo || value > hi)
    bad_value(option, fmt::format("an integer from {} to {}", lo, hi), text);
  return value;
}

std::int64_t time_unit_option(std::string_view option, std::string_view text) {
  std::int64_t value = 0;
  if (!whole_integer(text, value) || value < 0)
    bad_value(option, "a time unit H, an integer from 0 to S", text);
  return value;
}

int slow_factor_option(std::string_view text) {
  std::int64_t k = 0;
  if (!whole_integer(text, k) || k < 1 || k > particle::kMaxSlowFactor || (k & (k - 1)) != 0)
    bad_value("--slow-factor",
              fmt::format("a power of two from 1 to 2^{} = {}",
                          std::countr_zero(static_cast<unsigned>(particle::kMaxSlowFactor)),
                          particle::kMaxSlowFactor),
              text);
  return static_cast<int>(k);
}

particle::WallStop wall_stop_option(std::string_view text) {
  const auto reading = particle::wall_stop_from_name(text);
  if (!reading) bad_value("--wall-stop", "per-coordinate or whole-motion", text);
  return *reading;
}

particle::Overlap overlap_option(std::string_view text) {
  const auto reading = particle::overlap_from_name(text);
  if (!reading) bad_value("--overlap", "approaching or always", text);
  return *reading;
}

std::uint64_t seed_option(std::string_view text) {
  std::uint64_t seed = 0;
  if (!whole_integer(text, seed))
    bad_value("--seed",
              fmt::format("an integer from 0 to 2^64 - 1 = {}",
                          std::numeric_limits<std::uint64_t>::max()),
              text);
  return seed;
}

std::string path_option(std::string_view option, std::string_view text) {
  if (text.empty()) bad_value(option, "a file path", text);
  return std::string(text);
}

}  // namespace lab
