#include "rays/ray_generators.h"

#include <cmath>
#include <functional>

#include "geometry/input_error.h"
#include "rays/camera.h"
#include "rays/feature_rays.h"
#include "rays/isotropic_lines.h"
#include "rays/ray_file.h"

namespace raylab {
namespace {

const ParamDoc kSeedDoc{"seed", "1", "random seed (0 .. 2^63-1)"};
const ParamDoc kFovDoc{"fov", "45", "vertical field of view of the camera, degrees"};
const ParamDoc kFromDoc{"from", "1;0.6;1.4", "direction from the scene centre to the camera, x;y;z"};
const ParamDoc kCameraDoc{"camera", "outside",
                          "outside: the eye outside the scene box, framing it; inside: the eye inside the box, "
                          "0.9 of the way from its centre toward `from`, looking at the centre (for enclosed "
                          "scenes such as room:...,window=0; camera.h)"};

const std::vector<RayGeneratorDoc>& docs() {
  static const std::vector<RayGeneratorDoc> d = {
      {"primary", "primary:N",
       "Camera rays through pixel centres of a W×W image, W = round(sqrt(N)) (N is rounded to a square), in "
       "scanline order: ray i is pixel (i % W, i / W). The pinhole camera looks at the centre of the scene box from "
       "`from` at the distance where the bounding sphere fills the field of view (camera.h).",
       {kFovDoc, kFromDoc, kCameraDoc}},
      {"diffuse", "diffuse:N",
       "Cosine-weighted bounces from the surfaces the primary camera sees (surface_rays.h): origin offset off the "
       "surface (Wächter & Binder), unit direction, tmax = inf.",
       {kSeedDoc, kFovDoc, kFromDoc, kCameraDoc}},
      {"shadow", "shadow:N",
       "From the surfaces the primary camera sees toward uniform points of a square area light above the scene; "
       "direction = light - origin, tmax just below 1 (for occlusion queries).",
       {kSeedDoc, kFovDoc, kFromDoc, kCameraDoc}},
      {"ao", "ao:N",
       "Ambient-occlusion rays: cosine-weighted from the surfaces the primary camera sees, tmax = 0.1 x the scene "
       "diagonal.",
       {kSeedDoc, kFovDoc, kFromDoc, kCameraDoc}},
      {"lines", "lines:N",
       "Isotropic random lines through the scene's bounding sphere (centre of the box, radius 1.01 x half the "
       "diagonal) under the invariant measure of Cauchy-Crofton (isotropic_lines.h); each ray spans a whole chord.",
       {kSeedDoc}},
      {"edges", "edges:N",
       "Rays crossing the mesh from the outside exactly at a random point of a random edge (feature_rays.h); "
       "triangle meshes only.",
       {kSeedDoc}},
      {"vertices", "vertices:N",
       "Rays crossing the mesh from the outside exactly at a random vertex (feature_rays.h); triangle meshes only.",
       {kSeedDoc}},
      {"touching", "touching:N",
       "Rays through mesh vertices exactly, outside the tangent cone of the vertex's fan: each touches the surface at "
       "the vertex without crossing it there (decided exactly; feature_rays.h); triangle meshes only.",
       {kSeedDoc}},
      {"grazing", "grazing:N",
       "Rays aimed at points of silhouette edges (edges of two non-coplanar triangles), in the wedge where both faces "
       "lie on one side of the line, half of them nearly in a face's plane: touching, missing or crossing the surface "
       "by a few ulps (feature_rays.h); triangle meshes only.",
       {kSeedDoc}},
      {"file", "file:PATH",
       "The rays of a ray file (ray_file.h); everything after 'file:' is the path.",
       {}},
  };
  return d;
}

std::string prefix(const std::string& spec) { return "rays '" + spec + "': "; }

Vec3d read_from(SpecReader& r) {
  const std::string text = r.get_string("from", "");
  if (text.empty()) return kDefaultCameraFrom;
  Vec3d v;
  std::size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const std::size_t end = a < 2 ? text.find(';', start) : text.size();
    if (end == std::string::npos || !parse_double(std::string_view(text).substr(start, end - start), v[a]))
      throw InputError(prefix(r.spec().text) + "from=" + text + " is not three numbers x;y;z");
    start = end + 1;
  }
  if (v == Vec3d(0.0)) throw InputError(prefix(r.spec().text) + "from=" + text + " is the zero vector");
  return v;
}

Bounds3f checked_bounds(const Scene& scene, const std::string& spec) {
  const Bounds3f b = scene.bounds();
  if (b.empty() || !is_finite(b.lo) || !is_finite(b.hi))
    throw InputError(prefix(spec) + "the scene is empty or not finite");
  return b;
}

}  // namespace

std::vector<Ray> generate_rays(const std::string& spec, const Scene& scene, const FirstHitFunction& trace) {
  // A path may hold commas, colons and '=': everything after "file:" is taken verbatim.
  if (spec.rfind("file:", 0) == 0) {
    const std::string path = spec.substr(5);
    if (path.empty()) throw InputError(prefix(spec) + "missing path");
    return read_rays(path);
  }
  SpecReader r(parse_spec(spec));
  const std::string& name = r.spec().name;
  const RayGeneratorDoc* doc = nullptr;
  for (const auto& d : docs())
    if (d.name == name) doc = &d;
  if (!doc) {
    std::string list;
    for (const auto& n : ray_generator_names()) list += (list.empty() ? "" : ", ") + n;
    throw InputError(prefix(spec) + "unknown generator '" + name + "' (known: " + list + ")");
  }
  const auto count = static_cast<std::size_t>(r.get_positional_int("ray count", 1, kMaxRayCount));
  const bool camera_based = name == "primary" || name == "diffuse" || name == "shadow" || name == "ao";
  const double fov = camera_based ? r.get_double("fov", kDefaultFovDegrees, 1.0, 179.0) : kDefaultFovDegrees;
  const Vec3d from = camera_based ? read_from(r) : kDefaultCameraFrom;
  const CameraPlacement placement = parse_camera_placement(
      camera_based ? r.get_choice("camera", "outside", camera_placement_names()) : "outside");
  const auto seed = name == "primary" ? kDefaultRaySeed
                                      : static_cast<std::uint64_t>(r.get_int(
                                            "seed", static_cast<std::int64_t>(kDefaultRaySeed), 0,
                                            std::numeric_limits<std::int64_t>::max()));
  r.finish(doc->params);
  const Bounds3f bounds = checked_bounds(scene, spec);

  if (camera_based) {
    const Camera camera = placed_camera(placement, bounds, fov, from);
    if (name == "primary") {
      const int w = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(count)))));
      return image_rays(camera, w, w);
    }
    if (!trace) throw InputError(prefix(spec) + "needs a tracer for the primary hits");
    const SurfaceRayKind kind = name == "diffuse" ? SurfaceRayKind::diffuse
                                : name == "shadow" ? SurfaceRayKind::shadow
                                                   : SurfaceRayKind::ambient_occlusion;
    std::vector<Ray> rays = surface_rays(kind, scene, camera, count, seed, trace);
    if (rays.empty()) throw InputError(prefix(spec) + "the scene is not visible from the camera");
    return rays;
  }
  const Bounds3d b(Vec3d(bounds.lo), Vec3d(bounds.hi));
  const double diagonal = length(b.diagonal());
  if (name == "lines") {
    const double radius = 1.01 * 0.5 * diagonal;
    return isotropic_lines(b.center(), radius > 0.0 ? radius : 1.0, count, seed);
  }
  // edges, vertices, touching, grazing
  if (scene.instanced() || scene.mesh.size() == 0)
    throw InputError(prefix(spec) + "needs a triangle mesh; the scene is " +
                     (scene.instanced() ? "instanced" : "spheres only"));
  if (name == "touching") {
    try {
      return touching_vertex_rays(scene.mesh, count, 1e-2 * diagonal, seed);
    } catch (const InputError& e) {
      throw InputError(prefix(spec) + e.what());
    }
  }
  if (name == "grazing") {
    try {
      return grazing_edge_rays(scene.mesh, count, 1e-2 * diagonal, seed);
    } catch (const InputError& e) {
      throw InputError(prefix(spec) + e.what());
    }
  }
  try {
    return feature_rays(scene.mesh, name == "edges" ? MeshFeature::edge : MeshFeature::vertex, count,
                        1e-2 * diagonal, seed);
  } catch (const InputError& e) {
    throw InputError(prefix(spec) + "the mesh has no non-degenerate triangle");
  }
}

std::vector<RayGeneratorDoc> ray_generator_docs() { return docs(); }

std::vector<std::string> ray_generator_names() {
  std::vector<std::string> names;
  for (const auto& d : docs()) names.push_back(d.name);
  return names;
}

}  // namespace raylab
