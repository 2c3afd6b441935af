#pragma once
/// FNV-1a (Fowler, Noll, Vo) over raw bytes, for Aggregate::structure_hash: chain calls over an
/// accelerator's node and index arrays.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace raylab {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 14695981039346656037ull;

inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t h = kFnv1aOffsetBasis) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

/// Hashes a vector of trivially copyable elements.
template <class T>
std::uint64_t fnv1a(const std::vector<T>& v, std::uint64_t h = kFnv1aOffsetBasis) {
  return fnv1a(v.data(), v.size() * sizeof(T), h);
}

}  // namespace raylab
