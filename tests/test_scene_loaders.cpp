// Mesh files: valid files of every format, a corpus of malformed files, and the CGAL demo meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>

#include "geometry/input_error.h"
#include "scene/cgal_meshes.h"
#include "scene/file_format.h"
#include "scene/mesh_io.h"
#include "scene/scene.h"

namespace fs = std::filesystem;
using namespace raylab;

namespace {

const fs::path kData = RAYLAB_TEST_DATA;

/// A per-process scratch directory, removed at exit.
class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("raylab_scene_test_" + std::to_string(::getpid()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

Scene as_scene(TriangleMesh mesh) {
  Scene s;
  s.mesh = std::move(mesh);
  return s;
}

void expect_unit_cube(const TriangleMesh& m) {
  const Bounds3f b = m.bounds();
  EXPECT_EQ(b.lo, Vec3f(0.0f));
  EXPECT_EQ(b.hi, Vec3f(1.0f));
}

}  // namespace

TEST(LoaderValid, OffWithQuadsCommentsAndColours) {
  MeshLoadReport r;
  const TriangleMesh m = load_mesh((kData / "meshes" / "cube_quads.off").string(), &r);
  EXPECT_EQ(m.size(), 12u);
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(r.faces_read, 6u);
  EXPECT_EQ(r.polygons_triangulated, 6u);
  EXPECT_EQ(r.zero_area_triangles, 0u);
  EXPECT_EQ(r.faces_skipped, 0u);
  expect_unit_cube(m);
  EXPECT_TRUE(describe(as_scene(m)).closed);
}

TEST(LoaderValid, ObjWithNegativeAndSlashedIndices) {
  MeshLoadReport r;
  const TriangleMesh m = load_mesh((kData / "meshes" / "pyramid.obj").string(), &r);
  EXPECT_EQ(m.size(), 6u);
  EXPECT_EQ(r.faces_read, 5u);
  EXPECT_EQ(r.polygons_triangulated, 1u);
  const SceneInfo info = describe(as_scene(m));
  EXPECT_TRUE(info.closed);
  EXPECT_EQ(info.degenerate_triangles, 0u);
}

TEST(LoaderValid, PlyAsciiAndBinary) {
  for (const char* name : {"cube_ascii.ply", "cube_binary.ply", "cube_binary_be.ply"}) {
    SCOPED_TRACE(name);
    MeshLoadReport r;
    const TriangleMesh m = load_mesh((kData / "meshes" / name).string(), &r);
    EXPECT_EQ(m.size(), 12u);
    EXPECT_EQ(m.vertices.size(), 8u);
    expect_unit_cube(m);
    EXPECT_TRUE(describe(as_scene(m)).closed);
  }
  MeshLoadReport r;
  load_mesh((kData / "meshes" / "cube_binary.ply").string(), &r);
  EXPECT_EQ(r.polygons_triangulated, 6u);
}

TEST(LoaderValid, StlAsciiAndBinary) {
  const TriangleMesh tetra = load_mesh((kData / "meshes" / "tetra_ascii.stl").string());
  EXPECT_EQ(tetra.size(), 4u);
  EXPECT_EQ(tetra.vertices.size(), 4u);  // STL corners are merged by position
  EXPECT_TRUE(describe(as_scene(tetra)).closed);
  // The binary cube's header starts with "solid": the file size decides the format.
  const TriangleMesh cube = load_mesh((kData / "meshes" / "cube_binary.stl").string());
  EXPECT_EQ(cube.size(), 12u);
  EXPECT_EQ(cube.vertices.size(), 8u);
  expect_unit_cube(cube);
  EXPECT_TRUE(describe(as_scene(cube)).closed);
}

TEST(LoaderValid, ExtensionIsCaseInsensitive) {
  TempDir dir;
  fs::copy_file(kData / "meshes" / "cube_quads.off", dir / "CUBE.OFF");
  EXPECT_EQ(load_mesh((dir / "CUBE.OFF").string()).size(), 12u);
}

TEST(LoaderValid, RoundTripThroughEveryWriter) {
  TempDir dir;
  const TriangleMesh cube = load_mesh((kData / "meshes" / "cube_ascii.ply").string());
  for (const auto& [name, binary] : std::vector<std::pair<std::string, bool>>{
           {"a.off", false}, {"a.obj", false}, {"a.ply", false}, {"b.ply", true}, {"a.stl", false}, {"b.stl", true}}) {
    SCOPED_TRACE(name);
    const std::string path = (dir / name).string();
    save_mesh(cube, path, binary);
    const TriangleMesh back = load_mesh(path);
    EXPECT_EQ(back.size(), 12u);
    expect_unit_cube(back);
    EXPECT_TRUE(describe(as_scene(back)).closed);
  }
}

TEST(LoaderValid, ZeroAreaTrianglesAreCountedExactly) {
  TempDir dir;
  // Face 1 is collinear, face 2 repeats a corner (OpenMesh skips it), face 0 is fine.
  write_text(dir / "degenerate.off", "OFF\n4 3 0\n0 0 0\n1 1 1\n2 2 2\n0 1 0\n3 0 1 3\n3 0 1 2\n3 0 0 3\n");
  MeshLoadReport r;
  const TriangleMesh m = load_mesh((dir / "degenerate.off").string(), &r);
  EXPECT_EQ(r.faces_read, 3u);
  EXPECT_EQ(r.faces_skipped, 1u);
  EXPECT_EQ(m.size(), 2u);
  EXPECT_EQ(r.zero_area_triangles, 1u);
  EXPECT_EQ(describe(as_scene(m)).degenerate_triangles, 1u);
}

TEST(LoaderMalformed, EveryFileFailsWithOneLineNamingIt) {
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(kData / "malformed")) {
    const std::string path = entry.path().string();
    SCOPED_TRACE(path);
    ++files;
    try {
      load_mesh(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(entry.path().filename().string()), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
  EXPECT_GE(files, 40u);
}

TEST(LoaderMalformed, MessagesNameTheFault) {
  auto message = [](const std::string& name) {
    try {
      load_mesh((kData / "malformed" / name).string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("nan_coordinate.off").find(":4: vertex 1 has a non-finite coordinate"), std::string::npos);
  EXPECT_NE(message("float_overflow.off").find("non-finite"), std::string::npos);
  EXPECT_NE(message("ply_binary_inf.ply").find("vertex 1 has a non-finite coordinate"), std::string::npos);
  EXPECT_NE(message("huge_counts.off").find("4000000000 vertices"), std::string::npos);
  EXPECT_NE(message("index_out_of_range.off").find("face 0: vertex index 3"), std::string::npos);
  EXPECT_NE(message("obj_negative_out_of_range.obj").find("-4"), std::string::npos);
  EXPECT_NE(message("no_faces.off").find("no triangles"), std::string::npos);
  EXPECT_NE(message("stl_binary_truncated.stl").find("neither ASCII STL"), std::string::npos);
  EXPECT_NE(message("empty.off").find("empty file"), std::string::npos);
}

TEST(LoaderMalformed, MissingFileAndUnknownFormat) {
  EXPECT_THROW(load_mesh("/nonexistent/dir/mesh.off"), InputError);
  EXPECT_THROW(load_mesh((kData / "meshes").string() + "/"), InputError);
  TempDir dir;
  EXPECT_THROW(save_mesh(TriangleMesh{}, (dir / "x.xyz").string()), InputError);
}

TEST(LoaderCgal, NamesAndReferenceMeshes) {
  const auto names = cgal_mesh_names();
  EXPECT_GT(names.size(), 50u);
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_TRUE(std::binary_search(names.begin(), names.end(), "bunny00"));
  const auto refs = cgal_reference_meshes();
  ASSERT_FALSE(refs.empty());
  EXPECT_EQ(refs.front(), "bunny00");
  for (const auto& r : refs) EXPECT_TRUE(fs::is_regular_file(cgal_mesh_path(r))) << r;
}

TEST(LoaderCgal, Bunny) {
  MeshLoadReport r;
  const TriangleMesh m = load_mesh(cgal_mesh_path("bunny00"), &r);
  EXPECT_GT(m.size(), 30000u);
  EXPECT_EQ(r.faces_skipped, 0u);
}

TEST(LoaderCgal, UnknownNameListsValidOnes) {
  try {
    cgal_mesh_path("bunny_does_not_exist");
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bunny_does_not_exist"), std::string::npos);
    EXPECT_NE(msg.find("bunny00"), std::string::npos);
  }
  EXPECT_THROW(cgal_mesh_path("../meshes/bunny00"), InputError);
}

TEST(LoaderCgal, EveryDemoMeshLoadsOrFailsCleanly) {
  std::size_t loaded = 0;
  for (const auto& name : cgal_mesh_names()) {
    try {
      if (load_mesh(cgal_mesh_path(name)).size() > 0) ++loaded;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(loaded, 50u);
}

// Real-world quirks (issue 20): valid files that exporters write and that raylab once rejected.

namespace {

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string stl_facet(Vec3f a, Vec3f b, Vec3f c) {
  std::string s = "  facet normal 0 0 0\n    outer loop\n";
  for (const Vec3f& v : {a, b, c})
    s += "      vertex " + std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z) + "\n";
  return s + "    endloop\n  endfacet\n";
}

std::string load_error(const std::string& path) {
  try {
    load_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(LoaderQuirks, AsciiStlWithSeveralSolidsAndAnEmptyOneIsOneMesh) {
  TempDir dir;
  const Vec3f o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  write_text(dir / "multi.stl", "solid first part\n" + stl_facet(o, y, x) + "endsolid first part\n" +
                                    "solid empty\nendsolid empty\n" +
                                    "solid facet named solid\n" + stl_facet(o, x, z) + stl_facet(o, z, y) + stl_facet(x, y, z) +
                                    "endsolid facet named solid\n");
  MeshLoadReport r;
  const TriangleMesh m = load_mesh((dir / "multi.stl").string(), &r);
  EXPECT_EQ(m.size(), 4u);
  EXPECT_EQ(r.faces_read, 4u);
  EXPECT_EQ(m.vertices.size(), 4u) << "corners are merged across solids";
  EXPECT_TRUE(describe(as_scene(m)).closed);
  // Empty solids alone hold no triangles: that stays an error.
  write_text(dir / "empty.stl", "solid a\nendsolid a\nsolid b\nendsolid b\n");
  EXPECT_NE(load_error((dir / "empty.stl").string()).find("no triangles"), std::string::npos);
  // A stray word inside a solid is still malformed.
  write_text(dir / "stray.stl", "solid a\n" + stl_facet(o, y, x) + "stray\nendsolid a\n");
  EXPECT_NE(load_error((dir / "stray.stl").string()).find(":9: expected 'facet' or 'endsolid'"), std::string::npos);
}

TEST(LoaderQuirks, UnknownPlyHeaderLinesAreSkippedWithAWarning) {
  TempDir dir;
  const std::string path = (dir / "created_by.ply").string();
  write_text(path,
             "ply\nformat ascii 1.0\ncomment ok\nCreated by SomeExporter 1.2\nelement vertex 3\nproperty float x\n"
             "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  MeshLoadReport r;
  testing::internal::CaptureStderr();
  const TriangleMesh m = load_mesh(path, &r);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(m.size(), 1u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find(path + ":4: skipped a PLY header line"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("'Created'"), std::string::npos) << r.warnings[0];
  EXPECT_EQ(err, "raylab: warning: " + r.warnings[0] + "\n");
  // Binary data after such a header is read unchanged.
  std::string binary = read_bytes(kData / "meshes" / "cube_binary.ply");
  binary.insert(binary.find("element"), "exporter_version 3\nmade with care\n");
  write_text(dir / "binary.ply", binary);
  testing::internal::CaptureStderr();
  const TriangleMesh cube = load_mesh((dir / "binary.ply").string(), &r);
  EXPECT_EQ(r.warnings.size(), 2u);
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(cube.size(), 12u);
  expect_unit_cube(cube);
  // A file whose "header" never ends still fails, with one line and no warnings printed.
  write_text(dir / "endless.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nnot a header\n");
  testing::internal::CaptureStderr();
  EXPECT_NE(load_error((dir / "endless.ply").string()).find("no 'end_header'"), std::string::npos);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(LoaderQuirks, FilesWithoutExtensionAreToldByContent) {
  TempDir dir;
  const std::pair<const char*, std::size_t> files[] = {{"cube_quads.off", 12}, {"cube_binary.ply", 12}, {"cube_ascii.ply", 12},
                                                       {"tetra_ascii.stl", 4},  {"cube_binary.stl", 12}, {"pyramid.obj", 6}};
  for (const auto& [name, triangles] : files) {
    const std::string plain = (dir / fs::path(name).stem().string()).string() + "_" + fs::path(name).extension().string().substr(1);
    fs::copy_file(kData / "meshes" / name, plain, fs::copy_options::overwrite_existing);
    ASSERT_TRUE(has_no_extension(plain)) << plain;
    EXPECT_EQ(detect_file_format(plain), *format_by_extension(name)) << name;
    EXPECT_EQ(load_mesh(plain).size(), triangles) << name;
  }
  write_text(dir / "mystery", "this is no mesh\n");
  EXPECT_NE(load_error((dir / "mystery").string()).find("no extension, and the content is none of the formats"), std::string::npos);
  EXPECT_EQ(format_by_content("# exported\n\nv 0 0 0\n", 21), FileFormat::obj);
  EXPECT_EQ(format_by_content("  {\"asset\": {}}", 15), FileFormat::gltf);
  EXPECT_EQ(format_by_content("glTF\x02\0\0\0", 8), FileFormat::glb);
  EXPECT_EQ(format_by_content("<?xml version=\"1.0\"?>\n<COLLADA>", 31), FileFormat::collada);
  EXPECT_EQ(format_by_content("; FBX 7.4.0 project file\n", 25), FileFormat::fbx);
  EXPECT_EQ(format_by_content(std::string("\x4d\x4d\x06\0\0\0", 6), 6), FileFormat::three_ds);
  EXPECT_EQ(format_by_content("STCNOFF\n", 8), FileFormat::off);
  EXPECT_EQ(format_by_content("vertex 1 2 3\n", 13), std::nullopt);
}

TEST(LoaderQuirks, Utf16ObjGetsAnErrorThatSaysSo) {
  TempDir dir;
  const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::string le = "\xff\xfe", be;
  for (const char c : text) {
    le += c;
    le += '\0';
    be += '\0';
    be += c;
  }
  write_text(dir / "utf16.obj", le);
  write_text(dir / "utf16_be_no_bom", be);
  for (const char* name : {"utf16.obj", "utf16_be_no_bom"}) {
    const std::string msg = load_error((dir / name).string());
    EXPECT_NE(msg.find("UTF-16"), std::string::npos) << msg;
    EXPECT_EQ(msg.rfind((dir / name).string() + ": ", 0), 0u) << msg;
  }
  write_text(dir / "utf8.obj", text);
  EXPECT_EQ(load_mesh((dir / "utf8.obj").string()).size(), 1u);
}
