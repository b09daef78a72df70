// FNV-1a, 64 bits: a fast, stable (across runs and machines) hash of bytes, for checksums and
// for names derived from content; not for security.
#pragma once

#include <cstdint>
#include <string_view>

namespace physgrad {

inline std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

}  // namespace physgrad
