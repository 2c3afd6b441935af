#pragma once
/// FNV-1a (Fowler, Noll, Vo) over 64-bit words (then the remaining bytes), for
/// Aggregate::structure_hash: chain calls over an accelerator's node and index arrays. Words
/// rather than bytes make it 8 times faster on the gigabyte-sized arrays of dense grids; it is a
/// fingerprint for comparing builds, not a checksum with a published value.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace raylab {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 14695981039346656037ull;

inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t h = kFnv1aOffsetBasis) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * 1099511628211ull;
  }
  for (; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

/// Hashes a vector of trivially copyable elements.
template <class T, class Allocator>
std::uint64_t fnv1a(const std::vector<T, Allocator>& v, std::uint64_t h = kFnv1aOffsetBasis) {
  return fnv1a(v.data(), v.size() * sizeof(T), h);
}

}  // namespace raylab
