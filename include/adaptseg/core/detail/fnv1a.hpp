#pragma once
/// @file
/// FNV-1a, 64 bits (Fowler, Noll and Vo): the hash that names a network's weights
/// (network_identity.hpp) and a cached segmentation's file (CachedBackend). Not cryptographic:
/// it tells files and images apart, it does not defend against forgery.

#include <cstddef>
#include <cstdint>

namespace adaptseg::detail {

/// FNV-1a's offset basis: the hash of nothing, where a hash over several pieces starts.
inline constexpr std::uint64_t kFnv1aBasis = 14695981039346656037ull;

/// FNV-1a over `n` bytes at `bytes`, continuing from `h` (kFnv1aBasis for a new hash).
[[nodiscard]] inline std::uint64_t fnv1a(const void* bytes, std::size_t n, std::uint64_t h = kFnv1aBasis) noexcept {
  const auto* p = static_cast<const unsigned char*>(bytes);
  for (std::size_t k = 0; k < n; ++k) h = (h ^ p[k]) * 1099511628211ull;
  return h;
}

}  // namespace adaptseg::detail
