#include "accel/bvh/packed_triangles.h"

namespace raylab {

namespace {

TrianglePacket empty_packet() {
  TrianglePacket p;
  for (auto& vertex : p.v)
    for (auto& axis : vertex)
      for (float& x : axis) x = std::numeric_limits<float>::quiet_NaN();
  for (auto& id : p.prim) id = kInvalidId;
  return p;
}

}  // namespace

std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, std::vector<TrianglePacket>& out) {
  const std::size_t before = out.size();
  for (const bool spheres : {false, true}) {
    int lane = kPacketWidth;
    for (const std::uint32_t prim : prims) {
      if (scene.is_sphere(prim) != spheres) continue;
      if (lane == kPacketWidth) {
        out.push_back(empty_packet());
        lane = 0;
      }
      TrianglePacket& p = out.back();
      p.prim[lane] = prim;
      if (!spheres) {
        const auto& tri = scene.mesh.triangles[prim];
        for (int k = 0; k < 3; ++k) {
          const Vec3f& x = scene.mesh.vertices[tri[k]];
          for (int a = 0; a < 3; ++a) p.v[k][a][lane] = x[a];
        }
      }
      ++lane;
    }
  }
  return static_cast<std::uint32_t>(out.size() - before);
}

std::vector<IndexedPacket> index_packets(const Scene& scene, std::span<const TrianglePacket> packets) {
  std::vector<IndexedPacket> out(packets.size());
  for (std::size_t i = 0; i < packets.size(); ++i)
    for (int lane = 0; lane < kPacketWidth; ++lane) {
      const std::uint32_t prim = packets[i].prim[lane];
      out[i].prim[lane] = prim;
      const bool triangle = prim != kInvalidId && !scene.is_sphere(prim);
      for (int k = 0; k < 3; ++k) out[i].vertex[k][lane] = triangle ? scene.mesh.triangles[prim][k] : 0;
    }
  return out;
}

}  // namespace raylab
