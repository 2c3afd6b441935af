// Scenes as people have them (issue 20): glTF 2.0 files written here, read through Assimp, whose
// node tree becomes bases and instances beside flat geometry; checked for triangle counts,
// instance transforms and 0 mismatches against the exact oracle (which flattens everything) for
// several accelerators; and glTF faults rejected with one line.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <numbers>

#include "accel/bvh/primitive_bvh.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "accel/exact/contact_classes.h"
#include "accel/exact/exact_oracle.h"
#include "geometry/input_error.h"
#include "scene_test_files.h"
#include "rays/surface_rays.h"
#include "scene/scene_import.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;
using test::GltfBuffer;
using test::GltfDocument;
using test::GltfNode;
using test::quaternion;

class ImportDir {
 public:
  ImportDir() : path_(fs::temp_directory_path() / ("raylab_import_test_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~ImportDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
};

TriangleMesh sphere_mesh() { return make_scene("sphere:n=300")->mesh; }

void expect_near(const AffineTransform& got, const AffineTransform& want, const std::string& what) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      EXPECT_NEAR(got.m[r][c], want.m[r][c], 1e-5 * (1 + std::abs(want.m[r][c]))) << what << " [" << r << "][" << c << "]";
}

AffineTransform trs(const std::array<double, 3>& t, const Vec3d& axis, double radians, const std::array<double, 3>& s) {
  return AffineTransform::translation({t[0], t[1], t[2]}) * AffineTransform::rotation(axis, radians) *
         AffineTransform::scaling({s[0], s[1], s[2]});
}

/// Every accelerator of the list agrees with the exact oracle (the flattened scene) within its
/// stated bound (0 for raylab's own on these rays), and every hit lies on the primitive and
/// instance it names.
void expect_agreement_with_oracle(const std::shared_ptr<const Scene>& scene) {
  const auto oracle = make_accelerator("exact", scene);
  const double diagonal = length(Vec3d(scene->bounds().diagonal()));
  for (const std::string ray_spec : {"primary:4096", "lines:4096"}) {
    const auto rays = make_ray_set(ray_spec, scene);
    std::vector<RayContact> classes;
    const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{});
    EXPECT_GT(ref.hit_count, rays.size() / 20) << ray_spec;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit& h = ref.hits[i];
      if (!h.valid()) continue;
      const Vec3d on_ray = Vec3d(rays[i].org) + Vec3d(rays[i].dir) * double(h.t);
      ASSERT_LE(length(Vec3d(surface_at(*scene, rays[i], h).p) - on_ray), 1e-4 * (length(Vec3d(rays[i].org)) + diagonal))
          << ray_spec << " ray " << i << " prim " << h.prim << " instance " << h.instance;
    }
    for (const std::string accel : {"brute", "bvh", "bvh:width=8", "kdtree", "grid", "nested-grid", "octree", "bsp", "embree-robust"}) {
      const TraceResult got = trace_rays(*make_accelerator(accel, scene), rays, TraceOptions{});
      HitComparison c = compare_hits(rays, got.hits, ref.hits, diagonal);
      if (c.mismatches > 0) {  // the bound is per class: classify only when it matters
        if (classes.empty()) classes = classify_contacts(scene, rays);
        c = compare_hits(rays, got.hits, ref.hits, diagonal, &classes);
      }
      std::string why;
      EXPECT_TRUE(within_bound(accuracy_bound(accel), c, is_feature_ray_spec(ray_spec), &why))
          << accel << " " << ray_spec << ": " << why << " (" << c.false_hits << " false, " << c.missed_hits
          << " missed, " << c.wrong_t << " wrong t)";
      EXPECT_LE(c.ties, c.rays / 200) << accel << " " << ray_spec;
    }
  }
}

// A mesh under two nodes with different transforms is one base with two instances; a mesh used
// once is flattened into world space.
TEST(SceneImport, MeshUnderTwoNodesIsOneBaseWithTwoInstances) {
  ImportDir dir;
  GltfDocument doc;
  doc.meshes = {sphere_mesh(), test::unit_cube()};
  const double quarter = std::numbers::pi / 2;
  doc.nodes.resize(3);
  doc.nodes[0].mesh = 0;
  doc.nodes[0].translation = std::array<double, 3>{3, 0, 0};
  doc.nodes[1].mesh = 0;
  doc.nodes[1].translation = std::array<double, 3>{-3, 0, 0};
  doc.nodes[1].rotation = quaternion({0, 0, 1}, quarter);
  doc.nodes[1].scale = std::array<double, 3>{2, 2, 2};
  doc.nodes[2].mesh = 1;
  doc.nodes[2].translation = std::array<double, 3>{0, 4, 0};
  doc.roots = {0, 1, 2};
  for (const GltfBuffer buffer : {GltfBuffer::embedded, GltfBuffer::external, GltfBuffer::binary}) {
    const std::string path = dir / (buffer == GltfBuffer::binary ? "two.glb" : "two.gltf");
    test::write_gltf(path, doc, buffer);
    SCOPED_TRACE(path);
    SceneImportReport report;
    const Scene s = import_scene(path, &report);
    ASSERT_EQ(s.bases.size(), 1u);
    ASSERT_EQ(s.instances.size(), 2u);
    EXPECT_EQ(s.bases[0]->mesh.size(), doc.meshes[0].size());
    EXPECT_EQ(s.instances[0].base, 0u);
    EXPECT_EQ(s.instances[1].base, 0u);
    expect_near(s.instances[0].transform, AffineTransform::translation({3, 0, 0}), "instance 0");
    expect_near(s.instances[1].transform, trs({-3, 0, 0}, {0, 0, 1}, quarter, {2, 2, 2}), "instance 1");
    EXPECT_EQ(s.mesh.size(), 12u);
    EXPECT_EQ(s.mesh.bounds().lo, Vec3f(0, 4, 0));
    EXPECT_EQ(s.mesh.bounds().hi, Vec3f(1, 5, 1));
    EXPECT_EQ(report.meshes, 2u);
    EXPECT_EQ(report.flattened_meshes, 1u);
    EXPECT_EQ(report.instances, 2u);
    const SceneInfo info = describe(s);
    EXPECT_EQ(info.meshes, 2u);
    EXPECT_EQ(info.instances, 2u);
    EXPECT_EQ(info.triangles, 2 * doc.meshes[0].size() + 12);
    EXPECT_EQ(info.unique_triangles, doc.meshes[0].size() + 12);
    EXPECT_TRUE(info.closed);
  }
  const auto scene = make_scene(dir / "two.gltf");
  const auto top = make_accelerator("bvh:kernel=watertight", scene);  // the float instancing path
  const auto* primitives = dynamic_cast<const PrimitiveBvh*>(top.get());
  ASSERT_NE(primitives, nullptr);
  EXPECT_EQ(primitives->size(), 3u) << "two instances and the flat geometry";
  expect_agreement_with_oracle(scene);
}

// World transforms are products down a node tree three levels deep; a node matrix is read as
// column-major.
TEST(SceneImport, NodeTreeThreeLevelsDeep) {
  ImportDir dir;
  GltfDocument doc;
  doc.meshes = {sphere_mesh()};
  const double tilt = 0.5;
  doc.nodes.resize(5);
  doc.nodes[0].translation = std::array<double, 3>{1, 2, 3};
  doc.nodes[0].children = {1};
  doc.nodes[1].rotation = quaternion({1, 0, 0}, tilt);
  doc.nodes[1].children = {2, 3};
  doc.nodes[2].scale = std::array<double, 3>{0.5, 0.5, 0.5};
  doc.nodes[2].mesh = 0;
  doc.nodes[3].translation = std::array<double, 3>{0, 0, 2.2};
  doc.nodes[3].mesh = 0;
  const AffineTransform direct = AffineTransform::translation({-2.2, 0, 1}) * AffineTransform::rotation({0, 1, 1}, 1.0);
  doc.nodes[4].matrix = direct;
  doc.nodes[4].mesh = 0;
  doc.roots = {0, 4};
  const std::string path = dir / "deep.gltf";
  test::write_gltf(path, doc);
  const auto scene = make_scene(path);
  ASSERT_EQ(scene->bases.size(), 1u);
  ASSERT_EQ(scene->instances.size(), 3u);
  const AffineTransform top = AffineTransform::translation({1, 2, 3}) * AffineTransform::rotation({1, 0, 0}, tilt);
  expect_near(scene->instances[0].transform, top * AffineTransform::scaling({0.5, 0.5, 0.5}), "grandchild 2");
  expect_near(scene->instances[1].transform, top * AffineTransform::translation({0, 0, 2.2}), "grandchild 3");
  expect_near(scene->instances[2].transform, direct, "matrix node");
  EXPECT_EQ(scene->mesh.size(), 0u);
  EXPECT_EQ(describe(*scene).triangles, 3 * doc.meshes[0].size());
  expect_agreement_with_oracle(scene);
}

// Non-uniform scales, on a shared mesh (instances) and on a mesh used once (flattened).
TEST(SceneImport, NonUniformScale) {
  ImportDir dir;
  GltfDocument doc;
  doc.meshes = {sphere_mesh(), test::unit_cube()};
  doc.nodes.resize(3);
  doc.nodes[0].mesh = 0;
  doc.nodes[0].scale = std::array<double, 3>{1, 2, 3};
  doc.nodes[1].mesh = 0;
  doc.nodes[1].translation = std::array<double, 3>{6, 0, 0};
  doc.nodes[1].rotation = quaternion({1, 1, 0}, 0.7);
  doc.nodes[1].scale = std::array<double, 3>{3, 1, 0.5};
  doc.nodes[2].mesh = 1;
  doc.nodes[2].translation = std::array<double, 3>{0, 8, 0};
  doc.nodes[2].rotation = quaternion({0, 0, 1}, 0.3);
  doc.nodes[2].scale = std::array<double, 3>{4, 0.25, 2};
  doc.roots = {0, 1, 2};
  const std::string path = dir / "scaled.glb";
  test::write_gltf(path, doc, GltfBuffer::binary);
  const auto scene = make_scene(path);
  ASSERT_EQ(scene->instances.size(), 2u);
  expect_near(scene->instances[0].transform, AffineTransform::scaling({1, 2, 3}), "instance 0");
  expect_near(scene->instances[1].transform, trs({6, 0, 0}, {1, 1, 0}, 0.7, {3, 1, 0.5}), "instance 1");
  // The flattened cube: each corner is the transformed corner, rounded once to float.
  const AffineTransform cube_xf = trs({0, 8, 0}, {0, 0, 1}, 0.3, {4, 0.25, 2});
  ASSERT_EQ(scene->mesh.size(), 12u);
  for (const Vec3f& v : scene->mesh.vertices) {
    bool found = false;
    for (const Vec3f& c : test::unit_cube().vertices) found = found || length(Vec3d(v) - cube_xf.apply_point(Vec3d(c))) < 1e-5;
    EXPECT_TRUE(found) << v.x << " " << v.y << " " << v.z;
  }
  expect_agreement_with_oracle(scene);
}

// The flattened copy the oracle uses holds every instance and the flat geometry, in the order
// exact_oracle.h documents, and names hits like the instanced accelerators do (spheres too).
TEST(SceneImport, OracleFlattensBasesWithSpheresAndFlatGeometry) {
  auto tri_base = std::make_shared<Scene>();
  tri_base->mesh = test::unit_cube();
  auto mixed_base = std::make_shared<Scene>();
  mixed_base->mesh = test::unit_cube();
  mixed_base->spheres = {{{0.5f, 0.5f, 2.0f}, 0.5f}};
  auto s = std::make_shared<Scene>();
  s->spec = "mixed";
  s->mesh = test::unit_cube();
  s->spheres = {{{-3, 0, 0}, 1.0f}};
  s->bases = {tri_base, mixed_base};
  s->instances = {{AffineTransform::translation({3, 0, 0}), 1},
                  {AffineTransform::translation({0, 3, 0}), 0},
                  {AffineTransform::translation({0, 0, 6}) * AffineTransform::scaling({2, 2, 2}), 1}};
  const auto flat = flatten_instances(*s);
  EXPECT_EQ(flat->mesh.size(), 4 * 12u);
  EXPECT_EQ(flat->spheres.size(), 3u);
  EXPECT_EQ(flat->spheres[2].radius, 1.0f);
  EXPECT_EQ(describe(*s).primitives, 4 * 12.0 + 3);
  expect_agreement_with_oracle(s);
  // Spheres under a non-uniform scale cannot be flattened into spheres.
  s->instances.push_back({AffineTransform::scaling({1, 2, 1}), 1});
  EXPECT_THROW(flatten_instances(*s), InputError);
}

TEST(SceneImport, GltfAndGlbWithoutExtensionAreToldByContent) {
  ImportDir dir;
  test::write_gltf(dir / "scene_json", test::shared_cube_document());
  test::write_gltf(dir / "scene_binary", test::shared_cube_document(), GltfBuffer::binary);
  for (const char* name : {"scene_json", "scene_binary"}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(make_scene("file:" + dir / name)->instances.size(), 2u);
    EXPECT_EQ(make_scene(dir / name)->instances.size(), 2u) << "a bare path naming an existing file";
  }
}

// COLLADA through the same path: a geometry instanced by three nodes, one nested in another.
// Assimp repeats the vertices of every corner; they are merged, so the tetrahedron stays closed.
TEST(SceneImport, ColladaGeometryUnderThreeNodes) {
  ImportDir dir;
  std::ofstream(dir / "tet.dae") << test::collada_tetrahedron();
  const auto scene = make_scene(dir / "tet.dae");
  ASSERT_EQ(scene->bases.size(), 1u);
  ASSERT_EQ(scene->instances.size(), 3u);
  EXPECT_EQ(scene->bases[0]->mesh.vertices.size(), 4u);
  AffineTransform b = AffineTransform::scaling({2, 1, 1});
  b.m[1][3] = 1;
  expect_near(scene->instances[0].transform, AffineTransform::translation({3, 0, 0}), "a");
  expect_near(scene->instances[1].transform, b, "b");
  expect_near(scene->instances[2].transform, b * AffineTransform::translation({0, 0, 2}), "c");
  const SceneInfo info = describe(*scene);
  EXPECT_EQ(info.triangles, 12u);
  EXPECT_EQ(info.unique_triangles, 4u);
  EXPECT_TRUE(info.closed);
  expect_agreement_with_oracle(scene);
}

/// A cube's triangles beside a LINES, a LINE_STRIP, a LINE_LOOP and two POINTS primitives (with
/// and without indices), and a second mesh of lines only, placed by a node of its own: in all,
/// 3 + 4 + 3 + 2 = 12 line segments and 7 + 2 = 9 points, all of them away from the cube.
GltfDocument cube_lines_and_points() {
  GltfDocument doc;
  doc.meshes = {test::unit_cube(), TriangleMesh{}};
  const std::vector<Vec3f> far = {{5, 0, 0}, {6, 0, 0}, {6, 1, 0}, {5, 1, 0}, {5, 1, 1}, {6, 1, 1}, {6, 2, 2}};
  doc.primitives = {{0, test::GltfMode::lines, far, {0, 1, 1, 2, 2, 3}},
                    {0, test::GltfMode::line_strip, {far.begin(), far.begin() + 5}, {}},
                    {0, test::GltfMode::line_loop, {far.begin(), far.begin() + 3}, {}},
                    {0, test::GltfMode::points, far, {}},
                    {0, test::GltfMode::points, far, {4, 6}},
                    {1, test::GltfMode::lines, {far.begin(), far.begin() + 4}, {}}};
  doc.nodes = {test::trs_node(0, {0, 0, 0}), test::trs_node(1, {0, -9, 0})};
  doc.roots = {0, 1};
  return doc;
}

/// `raylab ARGS`: exit status, stdout and stderr.
struct ToolRun {
  int status = -1;
  std::string out, err;
};

ToolRun run_tool(const ImportDir& dir, const std::string& args) {
  const std::string out = dir / "tool.out", err = dir / "tool.err";
  const int raw = std::system((std::string(RAYLAB_TOOL_PATH) + " " + args + " >" + out + " 2>" + err + " </dev/null").c_str());
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

// Only faces of three or more indices are triangles (issue 29): lines and points are left out of
// the scene, counted apart in the load report and in describe(), and no triangle comes from them.
TEST(SceneImport, LinesAndPointsAreLeftOutAndCountedApart) {
  ImportDir dir;
  const GltfDocument doc = cube_lines_and_points();
  for (const GltfBuffer buffer : {GltfBuffer::embedded, GltfBuffer::binary}) {
    const std::string path = dir / (buffer == GltfBuffer::binary ? "lines.glb" : "lines.gltf");
    test::write_gltf(path, doc, buffer);
    SCOPED_TRACE(path);
    SceneImportReport report;
    const Scene s = import_scene(path, &report);
    EXPECT_EQ(report.lines, 12u);
    EXPECT_EQ(report.points, 9u);
    EXPECT_EQ(report.meshes, 1u) << "the mesh of lines only is no scene mesh";
    ASSERT_EQ(s.mesh.size(), 12u);
    EXPECT_TRUE(s.bases.empty());
    EXPECT_EQ(s.mesh.vertices.size(), 8u) << "no vertex of a line or point joins the triangles";
    EXPECT_EQ(s.bounds().lo, Vec3f(0, 0, 0));
    EXPECT_EQ(s.bounds().hi, Vec3f(1, 1, 1));
    const SceneInfo info = describe(s);
    EXPECT_EQ(info.triangles, 12u);
    EXPECT_EQ(info.unique_triangles, 12u);
    EXPECT_EQ(info.degenerate_triangles, 0u);
    EXPECT_EQ(info.lines, 12u);
    EXPECT_EQ(info.points, 9u);
    EXPECT_TRUE(info.closed);
  }
}

// A triangle with a repeated corner stays a (degenerate) triangle: it is no line. (The `assimp
// info` tool reports such triangles as lines: its aiProcess_FindDegenerates turns them into
// faces of two indices; raylab runs no such step.)
TEST(SceneImport, TriangleWithARepeatedCornerIsADegenerateTriangleNotALine) {
  ImportDir dir;
  GltfDocument doc;
  doc.meshes = {test::unit_cube()};
  doc.meshes[0].triangles.push_back({0, 0, 7});
  doc.nodes = {test::trs_node(0, {0, 0, 0})};
  doc.roots = {0};
  const std::string path = dir / "repeated_corner.gltf";
  test::write_gltf(path, doc);
  SceneImportReport report;
  const Scene s = import_scene(path, &report);
  EXPECT_EQ(s.mesh.size(), 13u);
  EXPECT_EQ(report.lines, 0u);
  const SceneInfo info = describe(s);
  EXPECT_EQ(info.triangles, 13u);
  EXPECT_EQ(info.degenerate_triangles, 1u);
  EXPECT_EQ(info.lines, 0u);
}

// The same for OBJ (read by OpenMesh, mesh_io.h): `l` polylines and `p` points are counted, not
// triangles; an OBJ of lines only is one error.
TEST(SceneImport, ObjLinesAndPointsAreLeftOut) {
  ImportDir dir;
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\nv 6 5 5\n";
  std::ofstream(dir / "tet.obj") << vertices << "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\nl 5 6\nl 1 5 6 2\np 5 6\n";
  const auto scene = make_scene(dir / "tet.obj");
  EXPECT_EQ(scene->mesh.size(), 4u);
  const SceneInfo info = describe(*scene);
  EXPECT_EQ(info.lines, 4u);
  EXPECT_EQ(info.points, 2u);
  EXPECT_TRUE(info.closed);
  std::ofstream(dir / "lines.obj") << vertices << "l 1 2 3\n";
  try {
    make_scene(dir / "lines.obj");
    ADD_FAILURE() << "an OBJ of lines only was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), dir / "lines.obj" + ": no triangles (2 lines, 0 points left out)");
  }
}

// `raylab info` prints the left-out counts beside the triangle counts (text and JSON), and the
// load warns about them on one line.
TEST(SceneImport, InfoPrintsLinesAndPointsLeftOut) {
  ImportDir dir;
  const std::string path = dir / "lines.gltf";
  test::write_gltf(path, cube_lines_and_points());
  const ToolRun text = run_tool(dir, "info " + path);
  ASSERT_EQ(text.status, 0) << text.err;
  for (const char* line : {"\ntriangles: 12\n", "\nunique_triangles: 12\n", "\nlines: 12\n", "\npoints: 9\n"})
    EXPECT_NE(text.out.find(line), std::string::npos) << line << " in\n" << text.out;
  EXPECT_EQ(text.err, "raylab: warning: " + path + ": left out 12 lines and 9 points (raylab traces triangles)\n");
  const ToolRun json = run_tool(dir, "info --json " + path);
  ASSERT_EQ(json.status, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["lines"], 12);
  EXPECT_EQ(j["points"], 9);
  const ToolRun plain = run_tool(dir, "info --json sphere:n=300");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(nlohmann::json::parse(plain.out)["lines"], 0);
}

std::string import_error(const std::string& path) {
  try {
    import_scene(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// Bad scene files: one line naming the file and the fault, never a crash (test_bad_input.cpp
// runs them through the tool for the exit status).
TEST(SceneImportBadInput, FaultsAreNamedOnOneLine) {
  ImportDir dir;
  const auto files = test::write_bad_scene_files(dir.str());
  EXPECT_GE(files.size(), 20u);
  for (const auto& f : files) {
    const std::string msg = import_error(f.path);
    SCOPED_TRACE(f.path + ": " + msg);
    EXPECT_EQ(msg.rfind(f.path + ":", 0), 0u);
    EXPECT_NE(msg.find(f.fault), std::string::npos);
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
  EXPECT_EQ(import_scene(dir / "whole.glb").instances.size(), 2u);
}

// A scene of lines and points only: one error line with their counts, exit status 2.
TEST(SceneImportBadInput, OnlyLinesAndPointsIsOneError) {
  ImportDir dir;
  GltfDocument doc = cube_lines_and_points();
  doc.meshes[0] = TriangleMesh{};
  const std::string path = dir / "only_lines.glb";
  test::write_gltf(path, doc, GltfBuffer::binary);
  EXPECT_EQ(import_error(path), path + ": no triangles (12 lines, 9 points left out)");
  const ToolRun r = run_tool(dir, "info " + path);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "raylab: error: " + path + ": no triangles (12 lines, 9 points left out)\n");
  EXPECT_EQ(r.out, "");
}

TEST(SceneImportBadInput, OpenMeshFormatsAreNotAssimps) {
  ImportDir dir;
  std::ofstream(dir / "a.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NE(import_error(dir / "a.off").find("OpenMesh"), std::string::npos);
}

}  // namespace
}  // namespace raylab
