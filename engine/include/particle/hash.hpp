#pragma once
// FNV-1a, 64 bits: a fixed, portable byte hash (std::hash is unspecified), used for state hashes
// and psweep's configuration ids.
#include <cstddef>
#include <cstdint>

namespace particle {

inline constexpr std::uint64_t kFnv1aBasis = 0xcbf29ce484222325ull;

// Continues hash h over `size` bytes; pass the result as h to hash several buffers as one.
inline std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t h = kFnv1aBasis) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < size; ++k) {
    h ^= bytes[k];
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace particle
