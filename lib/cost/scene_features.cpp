#include "cost/scene_features.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/input_error.h"
#include "scene/scene_spec.h"

namespace raylab {

namespace {

[[gnu::always_inline]] inline double triangle_area(const TriangleMesh& mesh, std::size_t t) {
  const Vec3f a = mesh.vertex(t, 0);
  return 0.5 * static_cast<double>(length(cross(mesh.vertex(t, 1) - a, mesh.vertex(t, 2) - a)));
}

/// Σ area, Σ √area, largest area and the box of a range of triangles.
struct AreaPass {
  double total = 0, sqrt_total = 0, largest = 0;
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
      pass.sqrt_total += std::sqrt(area);
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
      pass.sqrt_total += c.sqrt_total;
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
  f.sqrt_area_sum = pass.sqrt_total;
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
  if (scene.primitive_count() > 0) {
    f.box_area = static_cast<double>(box.surface_area());
    f.largest_extent = static_cast<double>(max_component(box.diagonal()));
  }
  if (f.box_area > 0) f.crossings = f.total_area / f.box_area;
  return f;
}

double spread_references(const SceneFeatures& f) {
  if (!(f.triangles > 0) || !(f.largest_extent > 0)) return 0.0;
  const double h = f.largest_extent / std::cbrt(f.primitives);
  const double perimeter_per_sqrt_area = std::sqrt(12.0 * std::sqrt(3.0));  // an equilateral triangle's
  return 0.75 * perimeter_per_sqrt_area * f.sqrt_area_sum / h + 1.5 * f.total_area / (h * h);
}

SceneFeatureTable load_scene_features(const std::vector<std::string>& scene_specs,
                                      const std::function<void(const std::string&)>& progress) {
  SceneFeatureTable table;
  for (const std::string& spec : scene_specs) {
    if (table.count(spec)) continue;
    std::optional<SceneFeatures>& f = table[spec];
    try {
      const auto scene = make_scene(spec);
      if (!scene->instanced()) f = scene_features(*scene);
      else if (progress) progress("scene " + spec + " left out of the scene-feature fits (instanced)");
    } catch (const InputError& e) {
      if (progress) progress("scene " + spec + " left out of the scene-feature fits (" + e.what() + ")");
    }
  }
  return table;
}

}  // namespace raylab
