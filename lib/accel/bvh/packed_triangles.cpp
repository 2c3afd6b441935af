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

std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, TrianglePacket* out) {
  TrianglePacket* next = out;
  for (const bool spheres : {false, true}) {
    int lane = kPacketWidth;
    for (const std::uint32_t prim : prims) {
      if (scene.is_sphere(prim) != spheres) continue;
      if (lane == kPacketWidth) {
        *next++ = empty_packet();
        lane = 0;
      }
      TrianglePacket& p = next[-1];
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
  return static_cast<std::uint32_t>(next - out);
}

std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, std::vector<TrianglePacket>& out) {
  std::size_t spheres = 0;
  for (const std::uint32_t prim : prims) spheres += scene.is_sphere(prim);
  const std::size_t before = out.size();
  out.resize(before + packed_leaf_packets(prims.size() - spheres, spheres));
  return pack_leaf(scene, prims, out.data() + before);
}

IndexedLeaves index_packets(const Scene& scene, std::span<const TrianglePacket> packets) {
  IndexedLeaves out;
  out.packets.resize(packets.size());
  std::vector<std::uint32_t> copy_of(scene.mesh.vertices.size(), kInvalidId);
  for (std::size_t i = 0; i < packets.size(); ++i)
    for (int lane = 0; lane < kPacketWidth; ++lane) {
      const std::uint32_t prim = packets[i].prim[lane];
      out.packets[i].prim[lane] = prim;
      const bool triangle = prim != kInvalidId && !scene.is_sphere(prim);
      for (int k = 0; k < 3; ++k) {
        std::uint32_t copy = 0;
        if (triangle) {
          const std::uint32_t v = scene.mesh.triangles[prim][k];
          if (copy_of[v] == kInvalidId) {
            copy_of[v] = static_cast<std::uint32_t>(out.vertices.size());
            out.vertices.push_back(scene.mesh.vertices[v]);
          }
          copy = copy_of[v];
        }
        out.packets[i].vertex[k][lane] = copy;
      }
    }
  out.vertices.push_back(Vec3f{});  // the spare: gather_packet reads one float past a vertex
  return out;
}

}  // namespace raylab
