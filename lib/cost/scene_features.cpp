#include "cost/scene_features.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

namespace raylab {

namespace {

[[gnu::always_inline]] inline double triangle_area(const TriangleMesh& mesh, std::size_t t) {
  const Vec3f a = mesh.vertex(t, 0);
  return 0.5 * static_cast<double>(length(cross(mesh.vertex(t, 1) - a, mesh.vertex(t, 2) - a)));
}

/// Σ area, largest area and the box of a range of triangles.
struct AreaPass {
  double total = 0, largest = 0;
  Bounds3f box;
};

/// Triangles (and vertices) per chunk of the pass: chunks run in parallel, their sums are added in
/// chunk order, so the features do not depend on the thread count.
constexpr std::size_t kChunk = 1 << 15;

}  // namespace

SceneFeatures scene_features(const Scene& scene) {
  SceneFeatures f;
  f.primitives = static_cast<double>(scene.primitive_count());
  f.triangles = static_cast<double>(scene.triangle_count());
  const TriangleMesh& mesh = scene.mesh;
  const std::size_t n = mesh.size(), vertices = mesh.vertices.size();
  // One pass over the areas (their sum and the largest) and the vertices' box, in chunks.
  auto chunk_pass = [&](std::size_t c) {
    AreaPass pass;  // local: stores through a chunk array would keep the sums out of registers
    for (std::size_t t = c * kChunk, end = std::min(n, t + kChunk); t < end; ++t) {
      const double area = triangle_area(mesh, t);
      pass.total += area;
      pass.largest = std::max(pass.largest, area);
    }
    // TriangleMesh::bounds: holds every triangle.
    for (std::size_t v = c * kChunk, end = std::min(vertices, v + kChunk); v < end; ++v)
      pass.box.extend(mesh.vertices[v]);
    return pass;
  };
  const std::size_t chunk_count = (std::max(n, vertices) + kChunk - 1) / kChunk;
  AreaPass pass;
  if (chunk_count <= 1) {
    // One chunk: on the calling thread. `auto` asks this before every choice, and a task
    // scheduler's first use in a process (its worker threads started) costs milliseconds.
    if (chunk_count == 1) pass = chunk_pass(0);
  } else {
    std::vector<AreaPass> chunks(chunk_count);
    tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t c) { chunks[c] = chunk_pass(c); });
    for (const AreaPass& c : chunks) {
      pass.total += c.total;
      pass.largest = std::max(pass.largest, c.largest);
      pass.box.extend(c.box);
    }
  }
  // Every stride-th area for the median.
  const std::size_t stride = std::max<std::size_t>(1, n / kMedianSample);
  std::vector<double> sample;
  sample.reserve(n / stride + 1);
  for (std::size_t t = 0; t < n; t += stride)
    if (const double area = triangle_area(mesh, t); area > 0) sample.push_back(area);
  f.total_area = pass.total;
  f.max_area = pass.largest;
  Bounds3f box = pass.box;
  if (!sample.empty()) {
    const auto mid = sample.begin() + static_cast<std::ptrdiff_t>(sample.size() / 2);
    std::nth_element(sample.begin(), mid, sample.end());
    f.median_area = *mid;
    f.area_ratio = f.max_area / f.median_area;
  }
  for (std::size_t s = 0; s < scene.spheres.size(); ++s)
    box.extend(scene.primitive_bounds(static_cast<unsigned>(n + s)));
  if (scene.primitive_count() > 0) f.box_area = static_cast<double>(box.surface_area());
  if (f.box_area > 0) f.crossings = f.total_area / f.box_area;
  return f;
}

}  // namespace raylab
