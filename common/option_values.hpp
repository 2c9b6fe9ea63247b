#pragma once
// psim's option values. CLI11 hands them over as text and they are read here: numbers as whole
// tokens with an optional sign and decimal digits only (CLI11's own conversion would read "010"
// as octal and wrap "-1" into an unsigned seed), each checked against its bound, with a message
// naming the option and the form it expects. Errors are particle::InputError (exit 2).
#include <cstdint>
#include <string>
#include <string_view>

#include "particle/options.hpp"

namespace lab {

// An integer in [lo, hi]: "--threads: expected an integer from 1 to 1024, got "abc"".
std::int64_t integer_option(std::string_view option, std::string_view text, std::int64_t lo,
                            std::int64_t hi);

// A time unit H >= 0 (the scene, read later, bounds it by S).
std::int64_t time_unit_option(std::string_view option, std::string_view text);

// K: a power of two from 1 to particle::kMaxSlowFactor.
int slow_factor_option(std::string_view text);

// A wall-stop reading by its name (particle::wall_stop_from_name), for --wall-stop.
particle::WallStop wall_stop_option(std::string_view text);

// An overlap reading by its name (particle::overlap_from_name), for --overlap.
particle::Overlap overlap_option(std::string_view text);

// Any integer in [0, 2^64): the seed is the generator's 64-bit state.
std::uint64_t seed_option(std::string_view text);

// A file to write: not empty.
std::string path_option(std::string_view option, std::string_view text);

}  // namespace lab
