#pragma once
// 64-bit FNV-1a (Fowler-Noll-Vo), the one copy in the library: the history's checksums
// (src/history/history_hash.*, docs/history.md "Checksums") and the run fingerprint's digest
// (src/services/steps/run_fingerprint.cpp) chain it byte by byte. Stored checksums and digests
// depend on these constants, so they never change. Not a cryptographic hash.
#include <cstddef>
#include <cstdint>
#include <span>

namespace combabc {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 14695981039346656037ull;
inline constexpr std::uint64_t kFnv1aPrime = 1099511628211ull;

// `hash` (kFnv1aOffsetBasis to start) continued over `bytes`.
constexpr std::uint64_t Fnv1a(std::span<const unsigned char> bytes,
                              std::uint64_t hash = kFnv1aOffsetBasis) {
  for (unsigned char b : bytes) {
    hash ^= b;
    hash *= kFnv1aPrime;
  }
  return hash;
}

}  // namespace combabc
