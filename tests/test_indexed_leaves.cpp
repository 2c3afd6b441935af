// Indexed leaves (`bvh:leaves=indexed`, packed_triangles.h): an IndexedPacket gathers back, bit for
// bit, the TrianglePacket pack_leaf made (triangle, sphere and partly filled packets), from a copy
// holding each vertex once in the packets' order; the BVH with indexed leaves finds the first hits
// and occlusions of packed leaves under every kernel, width and node kind; and its bytes are its
// nodes, its packets and its vertices.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "accel/bvh/bvh.h"
#include "accel/bvh/packed_triangles.h"
#include "scene/scene_spec.h"
#include "same_first_hits.h"

namespace raylab {
namespace {

/// Triangles of a soup beside spheres, so leaves hold both kinds of packet.
std::shared_ptr<const Scene> soup_and_spheres() {
  auto scene = std::make_shared<Scene>(*make_scene("soup:n=1500"));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 200; ++i) scene->spheres.push_back({Vec3f(u(rng), u(rng), u(rng)), 0.01f + 0.02f * u(rng)});
  return scene;
}

TEST(IndexedLeaves, GatherReproducesThePackedLeaves) {
  const auto scene = soup_and_spheres();
  std::vector<TrianglePacket> packed;
  std::vector<std::uint32_t> prims;
  for (std::uint32_t p = 0; p < scene->primitive_count(); ++p) {
    prims.push_back(p);
    if (prims.size() == 7 || p + 1 == scene->primitive_count()) {  // 7: every packet's second one is partly filled
      pack_leaf(*scene, prims, packed);
      prims.clear();
    }
  }
  const IndexedLeaves indexed = index_packets(*scene, packed);
  ASSERT_EQ(indexed.packets.size(), packed.size());
  EXPECT_EQ(indexed.vertices.size(), scene->mesh.vertices.size() + 1);  // each used vertex once, and the spare
  int spheres = 0, partial = 0;
  for (std::size_t i = 0; i < packed.size(); ++i) {
    SCOPED_TRACE("packet " + std::to_string(i));
    TrianglePacket gathered;
    gather_packet(*scene, indexed.vertices.data(), indexed.packets[i], gathered);
    EXPECT_EQ(indexed.packets[i].size(), packed[i].size());
    ASSERT_EQ(std::memcmp(gathered.prim, packed[i].prim, sizeof gathered.prim), 0);
    if (scene->is_sphere(packed[i].prim[0])) {
      ++spheres;  // tested by id: the vertices are not read
      continue;
    }
    partial += packed[i].size() < kPacketWidth;
    EXPECT_EQ(std::memcmp(gathered.v, packed[i].v, sizeof gathered.v), 0);  // NaN lanes included
  }
  EXPECT_GT(spheres, 0);
  EXPECT_GT(partial, 0);
}

TEST(IndexedLeaves, BvhFindsTheFirstHitsOfPackedLeaves) {
  const std::vector<std::shared_ptr<const Scene>> scenes = {
      make_scene("walls:n=12,angle=30"), make_scene("transformed:of=(sphere:n=2000),translate=1e4:-1e4:1e4"),
      soup_and_spheres()};
  for (const auto& scene : scenes) {
    const Bounds3f box = scene->bounds();
    for (const int width : {4, 8})
      for (const BvhNodes nodes : {BvhNodes::full, BvhNodes::quantized})
        for (const int kernel : {0, 1, 2}) {
          BvhConfig config;
          config.threads = 1;
          config.width = width;
          config.nodes = nodes;
          config.robust = kernel != 2;
          config.kernel = kernel == 0 ? KernelChoice::certified : KernelChoice::watertight;
          const Bvh packed(scene, config);
          config.leaves = BvhLeaves::indexed;
          const Bvh indexed(scene, config);
          EXPECT_TRUE(packed.indexed().packets.empty());
          EXPECT_FALSE(indexed.indexed().packets.empty());
          const int hits = test::expect_same_first_hits(
              packed, indexed, box, static_cast<unsigned>(width + 10 * kernel), 2000,
              scene->spec + " width " + std::to_string(width) + " kernel " + std::to_string(kernel));
          EXPECT_GT(hits, 100);
        }
  }
}

TEST(IndexedLeaves, BytesAreTheNodesThePacketsAndTheVertices) {
  const auto scene = make_scene("sphere:n=20000");
  for (const BvhNodes nodes : {BvhNodes::full, BvhNodes::quantized}) {
    BvhConfig config;
    config.threads = 1;
    config.width = 8;
    config.nodes = nodes;
    const Bvh packed(scene, config);
    config.leaves = BvhLeaves::indexed;
    const Bvh indexed(scene, config);
    const std::size_t packets = indexed.indexed().packets.size();
    const std::size_t node_bytes = packed.stats().bytes - packets * sizeof(TrianglePacket);
    const std::size_t vertices = scene->mesh.vertices.size() + 1;  // a closed sphere: every vertex is used; the spare
    EXPECT_EQ(indexed.indexed().vertices.size(), vertices);
    EXPECT_EQ(indexed.stats().bytes, node_bytes + packets * sizeof(IndexedPacket) + vertices * sizeof(Vec3f));
    EXPECT_LT(indexed.stats().bytes, packed.stats().bytes * 3 / 4);  // 64 of a packet's 160 bytes, plus the vertices
  }
}

}  // namespace
}  // namespace raylab
