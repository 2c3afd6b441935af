#include "scene/scene_spec.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>

#include "geometry/input_error.h"
#include "scene/cgal_meshes.h"
#include "scene/file_format.h"
#include "scene/mesh_io.h"
#include "scene/procedural.h"
#include "scene/scene_import.h"

namespace raylab {
namespace {

constexpr std::int64_t kMaxSeed = std::numeric_limits<std::int64_t>::max();

const SceneKindDoc& kind(const std::string& name) {
  for (const auto& k : scene_kinds())
    if (k.name == name) return k;
  throw InputError("internal: no scene kind " + name);
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string kind_list() {
  std::string out;
  for (const auto& k : scene_kinds()) out += (out.empty() ? "" : ", ") + k.name;
  return out;
}

bool is_kind(const std::string& name) {
  const auto& kinds = scene_kinds();
  return std::any_of(kinds.begin(), kinds.end(), [&](const SceneKindDoc& k) { return k.name == name; });
}

/// The one positional argument of `cgal:NAME` / `file:PATH`, with no key=value items.
std::string single_argument(const SpecString& spec, const std::string& what) {
  if (spec.positional.size() != 1) throw InputError("spec " + quoted(spec.text) + ": expected " + spec.name + ":" + what);
  SpecString rest = spec;
  rest.positional.clear();
  SpecReader(rest).finish(kind(spec.name).params);
  return spec.positional.front();
}

std::shared_ptr<Scene> mesh_scene(const std::string& path) {
  auto s = std::make_shared<Scene>();
  MeshLoadReport report;
  s->mesh = load_mesh(path, &report);
  s->left_out_lines = report.lines;
  s->left_out_points = report.points;
  return s;
}

/// A scene file: one mesh through OpenMesh, or a scene with a node tree through Assimp.
std::shared_ptr<Scene> file_scene(const std::string& path) {
  if (file_format_doc(detect_file_format(path)).library == FileLibrary::openmesh) return mesh_scene(path);
  return std::make_shared<Scene>(import_scene(path));
}

bool is_regular_file(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

/// Three finite numbers separated by `sep`, e.g. `1e4:0:-2` (key names the parameter).
Vec3d parse_vector(const std::string& spec, const std::string& key, const std::string& text, char sep) {
  Vec3d v;
  std::size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const std::size_t end = a < 2 ? text.find(sep, start) : text.size();
    if (end == std::string::npos || !parse_double(std::string_view(text).substr(start, end - start), v[a]))
      throw InputError("spec " + quoted(spec) + ": " + key + "=" + text + " is not three numbers separated by '" +
                       std::string(1, sep) + "'");
    start = end + 1;
  }
  return v;
}

/// `AXIS:DEG` with AXIS x, y, z or a;b;c.
void parse_rotation(const std::string& spec, const std::string& text, Vec3d& axis, double& degrees) {
  const std::size_t colon = text.rfind(':');
  const std::string what = "spec " + quoted(spec) + ": rotate=" + text;
  if (colon == std::string::npos || !parse_double(std::string_view(text).substr(colon + 1), degrees) ||
      std::abs(degrees) > 1e6)
    throw InputError(what + " is not AXIS:DEG (AXIS x, y, z or a;b;c; |DEG| <= 1e6)");
  const std::string a = text.substr(0, colon);
  if (a == "x") axis = {1, 0, 0};
  else if (a == "y") axis = {0, 1, 0};
  else if (a == "z") axis = {0, 0, 1};
  else axis = parse_vector(spec, "rotate axis", a, ';');
  if (!(length(axis) > 0.0) || !std::isfinite(length(axis))) throw InputError(what + ": the axis is the zero vector");
}

std::shared_ptr<Scene> build(const std::string& text) {
  const std::string head = text.substr(0, text.find(':'));
  // A bare path: one with a scene file extension, or the name of an existing file (which may
  // have no extension); a scene kind's name always means the kind.
  if (!is_kind(head) && (format_by_extension(text) || is_regular_file(text))) return file_scene(text);

  const SpecString spec = parse_spec(text);
  const std::string& name = spec.name;
  if (name == "cgal") return mesh_scene(cgal_mesh_path(single_argument(spec, "NAME")));
  if (name == "file") return file_scene(single_argument(spec, "PATH"));
  if (!is_kind(name))
    throw InputError("spec " + quoted(text) + ": unknown scene kind " + quoted(name) + " (valid: " + kind_list() +
                     ", or a scene file: a path ending in " + known_extensions() + ", or an existing file)");

  SpecReader r(spec);
  const auto& params = kind(name).params;
  auto scene = std::make_shared<Scene>();
  if (name == "sphere") {
    SphereConfig c;
    c.triangles = r.get_int("n", c.triangles, 8, std::int64_t{1} << 27);
    c.radius = r.get_double("radius", c.radius, 1e-30, 1e30);
    r.finish(params);
    *scene = make_sphere(c);
  } else if (name == "sphereflake") {
    SphereflakeConfig c;
    c.depth = static_cast<int>(r.get_int("depth", c.depth, 0, 7));
    c.as_triangles = r.get_choice("as", "spheres", {"spheres", "triangles"}) == "triangles";
    c.tess = static_cast<int>(r.get_int("tess", c.tess, 2, 64));
    r.finish(params);
    *scene = make_sphereflake(c);
  } else if (name == "stadium") {
    StadiumConfig c;
    const std::string object = r.get_string("object", "sphere:n=5000");
    c.ratio = r.get_double("ratio", c.ratio, 1, 1e6);
    c.segments = static_cast<int>(r.get_int("segments", c.segments, 8, 4096));
    c.tiers = static_cast<int>(r.get_int("tiers", c.tiers, 1, 256));
    r.finish(params);
    *scene = make_stadium(*make_scene(object), c);
  } else if (name == "grass") {
    GrassConfig c;
    c.blades = r.get_int("blades", c.blades, 1, std::int64_t{1} << 26);
    c.height = r.get_double("height", c.height, 1e-9, 1e3);
    c.width = r.get_double("width", c.width, 1e-9, 1e3);
    c.seed = static_cast<std::uint64_t>(r.get_int("seed", 1, 0, kMaxSeed));
    r.finish(params);
    *scene = make_grass(c);
  } else if (name == "walls") {
    WallsConfig c;
    c.walls = r.get_int("n", c.walls, 1, std::int64_t{1} << 24);
    c.angle_degrees = r.get_double("angle", c.angle_degrees, -360, 360);
    c.length = r.get_double("length", c.length, 1e-6, 1e6);
    c.thickness = r.get_double("thickness", c.thickness, 1e-9, 1e6);
    c.spacing = r.get_double("spacing", c.spacing, 1e-9, 1e6);
    r.finish(params);
    *scene = make_walls(c);
  } else if (name == "room") {
    RoomConfig c;
    const std::string object = r.get_string("of", "cgal:bunny00");
    c.margin = r.get_double("margin", c.margin, 0.01, 100);
    c.window = r.get_double("window", c.window, 0.0, 0.95);
    r.finish(params);
    *scene = make_room(*make_scene(object), c);
  } else if (name == "soup") {
    SoupConfig c;
    c.triangles = r.get_int("n", c.triangles, 1, std::int64_t{1} << 27);
    c.size = r.get_double("size", c.size, 0, 1);
    c.seed = static_cast<std::uint64_t>(r.get_int("seed", 1, 0, kMaxSeed));
    r.finish(params);
    *scene = make_soup(c);
  } else if (name == "dust") {
    DustConfig c;
    c.triangles = r.get_int("n", c.triangles, 1, std::int64_t{1} << 27);
    c.size = r.get_double("size", c.size, 0, 1);
    c.seed = static_cast<std::uint64_t>(r.get_int("seed", 1, 0, kMaxSeed));
    r.finish(params);
    *scene = make_dust(c);
  } else if (name == "needles") {
    NeedlesConfig c;
    c.needles = r.get_int("n", c.needles, 1, std::int64_t{1} << 27);
    c.length = r.get_double("length", c.length, 1e-9, 1e6);
    c.width = r.get_double("width", c.width, 0, 1e6);
    r.finish(params);
    *scene = make_needles(c);
  } else if (name == "fan") {
    FanConfig c;
    c.triangles = r.get_int("n", c.triangles, 3, std::int64_t{1} << 27);
    c.radius = r.get_double("radius", c.radius, 1e-9, 1e6);
    c.height = r.get_double("height", c.height, 1e-9, 1e6);
    r.finish(params);
    *scene = make_fan(c);
  } else if (name == "row") {
    NearMissRowConfig c;
    c.triangles = r.get_int("n", c.triangles, 1, std::int64_t{1} << 27);
    c.radius = r.get_double("radius", c.radius, 1e-9, 1e6);
    c.gap = r.get_double("gap", c.gap, 1e-12, c.radius / 4);
    r.finish(params);
    *scene = make_near_miss_row(c);
  } else if (name == "subdivided") {
    const std::string of = r.get_string("of", "cgal:bunny00");
    const int levels = static_cast<int>(r.get_int("levels", 1, 0, kMaxSubdivisionLevels));
    r.finish(params);
    *scene = make_subdivided(*make_scene(of), levels);
  } else if (name == "decimated") {
    const std::string of = r.get_string("of", "cgal:bunny00");
    const std::int64_t faces = r.get_int("faces", 1000, 1, std::int64_t{1} << 27);
    r.finish(params);
    *scene = make_decimated(*make_scene(of), faces);
  } else if (name == "transformed") {
    TransformedConfig c;
    const std::string of = r.get_string("of", "cgal:bunny00");
    const std::string rotate = r.get_string("rotate", "z:0");
    const std::string translate = r.get_string("translate", "0:0:0");
    c.scale = r.get_double("scale", 1.0, 1e-30, 1e30);
    r.finish(params);
    parse_rotation(text, rotate, c.axis, c.degrees);
    c.translate = parse_vector(text, "translate", translate, ':');
    *scene = make_transformed(*make_scene(of), c);
  } else if (name == "instances") {
    InstancesConfig c;
    const std::string of = r.get_string("of", "cgal:bunny00");
    c.count = r.get_int("count", c.count, 1, std::int64_t{1} << 24);
    c.seed = static_cast<std::uint64_t>(r.get_int("seed", 1, 0, kMaxSeed));
    r.finish(params);
    *scene = make_instances(make_scene(of), c);
  }
  return scene;
}

}  // namespace

namespace {

/// Scenes nest (`stadium:object=(...)`); deeper nesting is refused before anything is built, so a
/// hostile spec can neither recurse without bound nor grow an error message quadratically (the
/// fuzz and bad-input tests found both: 3000 levels took minutes, 10^5 levels ran out of memory).
constexpr int kMaxSceneNesting = 16;
thread_local int g_scene_nesting = 0;

std::string abbreviated(const std::string& s) { return s.size() <= 80 ? s : s.substr(0, 80) + "..."; }

/// Every vertex and sphere of the scene's flat geometry is finite.
void require_finite(const Scene& scene, const std::string& spec) {
  for (const auto& v : scene.mesh.vertices)
    if (!is_finite(v)) throw InputError("spec " + quoted(spec) + ": the scene has a non-finite vertex coordinate");
  for (const auto& sp : scene.spheres)
    if (!is_finite(sp.center) || !std::isfinite(sp.radius) || !is_finite(sp.bounds().hi) || !is_finite(sp.bounds().lo))
      throw InputError("spec " + quoted(spec) + ": the scene has a sphere with a non-finite centre or radius");
}

}  // namespace

std::shared_ptr<const Scene> make_scene(const std::string& spec) {
  int open = 0, deepest = g_scene_nesting;
  for (char c : spec) {
    if (c == '(') deepest = std::max(deepest, g_scene_nesting + ++open);
    if (c == ')') --open;
  }
  if (deepest >= kMaxSceneNesting)
    throw InputError("spec " + quoted(abbreviated(spec)) + ": scenes nested deeper than " +
                     std::to_string(kMaxSceneNesting) + " levels");
  struct NestingGuard {
    NestingGuard() { ++g_scene_nesting; }
    ~NestingGuard() { --g_scene_nesting; }
  } guard;
  std::shared_ptr<Scene> scene;
  try {
    scene = build(spec);
  } catch (const InputError& e) {
    // Errors of the generators name only the kind; prefix the spec unless the message names it.
    const std::string msg = e.what();
    if (msg.find(spec) != std::string::npos) throw;
    throw InputError("spec " + quoted(spec) + ": " + msg);
  }
  scene->spec = spec;
  require_finite(*scene, spec);
  for (const auto& base : scene->bases)
    if (base) require_finite(*base, spec);
  if (scene->instanced()) require_valid_instances(*scene);
  if (scene->total_primitive_count() == 0) throw InputError("spec " + quoted(spec) + ": the scene is empty");
  return scene;
}

const std::vector<SceneKindDoc>& scene_kinds() {
  static const std::vector<SceneKindDoc> kinds = {
      {"cgal", "a CGAL demo mesh by name: cgal:bunny00 (see cgal_mesh_names())", {}},
      {"file", "a scene file: file:PATH, or just PATH (formats and readers below; no extension: told by content)", {}},
      {"sphere", "a UV sphere with pole fans (closed)",
       {{"n", "5000", "about this many triangles, in [8, 2^27]"}, {"radius", "1", "radius"}}},
      {"sphereflake", "Haines' SPD sphereflake: 9 children of radius 1/3 per sphere, recursively",
       {{"depth", "4", "levels of children, in [0, 7]: (9^(depth+1)-1)/8 spheres"},
        {"as", "spheres", "spheres | triangles"},
        {"tess", "8", "with as=triangles: UV-sphere stacks (2*tess slices), in [2, 64]"}}},
      {"stadium", "teapot in a stadium: a small object at the goal line of a large sparse stadium",
       {{"object", "sphere:n=5000", "the object's scene spec (parenthesise nested specs)"},
        {"ratio", "1000", "field length over the object's bounding-box diagonal, in [1, 1e6]"},
        {"segments", "96", "segments around the stadium, in [8, 4096]"},
        {"tiers", "8", "tiers of stands, in [1, 256]"}}},
      {"grass", "thin blades (3 triangles each) uniformly on the unit square",
       {{"blades", "10000", "number of blades, in [1, 2^26]"},
        {"height", "0.05", "blade height"},
        {"width", "0.004", "blade width at the base"},
        {"seed", "1", "random seed"}}},
      {"walls", "long thin walls (boxes of 12 triangles) in parallel rows, rotated about y",
       {{"n", "100", "number of walls, in [1, 2^24]"},
        {"angle", "30", "rotation about the vertical axis in degrees, in [-360, 360]"},
        {"length", "10", "wall length"},
        {"thickness", "0.05", "wall thickness"},
        {"spacing", "0.5", "distance between rows"}}},
      {"room", "an object inside a box room, windows in the three faces toward the default camera unless window=0",
       {{"of", "cgal:bunny00", "the object's scene spec (parenthesise nested specs)"},
        {"margin", "0.25", "room grows the object's box by margin x its largest extent per side, in [0.01, 100]"},
        {"window", "0.8",
         "side of each window over its face's side, in [0.05, 0.95]; 0: a closed room (trace it with "
         "camera=inside rays)"}}},
      {"soup", "independent random triangles in the unit cube",
       {{"n", "10000", "number of triangles, in [1, 2^27]"},
        {"size", "0", "triangle size; 0 = n^(-1/3)"},
        {"seed", "1", "random seed"}}},
      {"dust", "tiny random triangles in the unit cube: almost every ray escapes (where log N fails)",
       {{"n", "10000", "number of triangles, in [1, 2^27]"},
        {"size", "0", "triangle size; 0 = 0.1/sqrt(n), about 0.01 triangles met per line"},
        {"seed", "1", "random seed"}}},
      {"needles", "parallel thin needles along the cube diagonal, whose boxes all overlap (where log N fails)",
       {{"n", "1024", "number of needles (one triangle each), in [1, 2^27]"},
        {"length", "1.5", "needle length"},
        {"width", "0", "needle width at its middle; 0 = a quarter of the lattice spacing"}}},
      {"fan", "a cone of n triangles around one apex of valence n (where log N fails)",
       {{"n", "4096", "number of triangles, in [3, 2^27]"}, {"radius", "1", "rim radius"}, {"height", "0.5", "apex height"}}},
      {"row", "a near-miss row: n triangles along the x axis, each passing within `gap` of it (where log N fails)",
       {{"n", "1024", "number of triangles, in [1, 2^27]"},
        {"gap", "0.001", "distance of every triangle from the axis, in (0, radius/4]"},
        {"radius", "0.25", "size of each triangle"}}},
      {"subdivided", "Loop subdivision (OpenMesh) of a triangle scene",
       {{"of", "cgal:bunny00", "the scene to subdivide"}, {"levels", "1", "levels (x4 triangles each), in [0, 13]; refused past 2^27 triangles or what physical memory holds"}}},
      {"decimated", "quadric decimation (OpenMesh) of a triangle scene",
       {{"of", "cgal:bunny00", "the scene to decimate"}, {"faces", "1000", "target triangle count, in [1, 2^27]"}}},
      {"transformed", "a scene under a similarity: rotated, scaled and moved (far from the origin, or tiny)",
       {{"of", "cgal:bunny00", "the scene to transform"},
        {"rotate", "z:0", "AXIS:DEG, AXIS x | y | z | a;b;c: rotation about the axis through the origin"},
        {"translate", "0:0:0", "X:Y:Z, applied after rotation and scaling"},
        {"scale", "1", "uniform scale about the origin, in [1e-30, 1e30]"}}},
      {"instances", "copies of a scene on a grid, each slightly rotated (transforms only)",
       {{"of", "cgal:bunny00", "the base scene"},
        {"count", "1000", "number of instances, in [1, 2^24]"},
        {"seed", "1", "random seed of the rotations"}}},
  };
  return kinds;
}

}  // namespace raylab
