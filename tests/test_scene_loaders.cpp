// Mesh files: valid files of every format, a corpus of malformed files, and the CGAL demo meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "geometry/input_error.h"
#include "scene/cgal_meshes.h"
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
