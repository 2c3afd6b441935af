#pragma once
/// Unsigned little-endian integers in file bytes, as binary STL, glTF (GLB), FBX and 3DS store
/// their counts and offsets.
#include <cstdint>
#include <string_view>

namespace raylab {

/// The `bytes`-byte (at most 8) unsigned little-endian integer at `at`; the caller checks that
/// [at, at + bytes) lies within `data`.
inline std::uint64_t read_le(std::string_view data, std::size_t at, std::size_t bytes) {
  std::uint64_t v = 0;
  for (std::size_t i = bytes; i-- > 0;) v = v << 8 | static_cast<unsigned char>(data[at + i]);
  return v;
}

}  // namespace raylab
