#pragma once
/// The binary BVH every builder produces; wide layouts are collapsed from it.
#include <cstdint>
#include <vector>

#include "geometry/bounds.h"

namespace raylab {

/// Builders keep every leaf at depth <= kBvhMaxDepth (they fall back to median splits below
/// depth kBvhMaxDepth - 32, and median splits of < 2^32 references finish within 32 levels), so
/// traversal stacks of kBvhMaxDepth + 1 entries never overflow.
inline constexpr int kBvhMaxDepth = 64;

/// 32 bytes. An interior node (count = 0) has children `first` and `first + 1`; a leaf holds
/// primitive references prims[first, first + count).
struct Bvh2Node {
  Bounds3f box;
  std::uint32_t first = 0;
  std::uint32_t count = 0;
  bool is_leaf() const { return count > 0; }
};
static_assert(sizeof(Bvh2Node) == 32);

struct Bvh2 {
  std::vector<Bvh2Node> nodes;       ///< node 0 is the root
  std::vector<std::uint32_t> prims;  ///< leaf references; a primitive may appear more than once (SBVH)
  std::size_t primitive_count = 0;   ///< primitives the tree was built over
};

}  // namespace raylab
