// Replays every seed input (tests/fuzz/corpus/<target>/) and every crash input the fuzzers
// found (tests/fuzz/regressions/<target>/) through the fuzz targets' own code
// (tests/fuzz/fuzz_targets.h), so fixed crashes stay fixed in the normal (and sanitized) suite
// without clang or libFuzzer.
#include <gtest/gtest.h>

#include <filesystem>
#include <algorithm>
#include <fstream>
#include <iterator>

#include "fuzz/fuzz_targets.h"

namespace fs = std::filesystem;

namespace {

const fs::path kFuzz = fs::path(RAYLAB_TEST_DATA).parent_path() / "fuzz";

std::size_t replay(const std::string& target, const std::function<void(const std::uint8_t*, std::size_t)>& run) {
  std::size_t n = 0;
  for (const char* kind : {"corpus", "regressions"}) {
    const fs::path dir = kFuzz / kind / target;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      if (!e.is_regular_file() || e.path().filename().string()[0] == '.') continue;
      std::ifstream in(e.path(), std::ios::binary);
      const std::vector<char> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
      SCOPED_TRACE(e.path().string());
      run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      ++n;
    }
  }
  return n;
}

}  // namespace

TEST(FuzzRegressions, MeshLoaders) {
  for (const std::string ext : {"off", "obj", "ply", "stl"})
    EXPECT_GT(replay("mesh_" + ext, [&](const std::uint8_t* d, std::size_t s) { raylab::fuzz::mesh_loader(d, s, "." + ext); }), 0u) << ext;
}

TEST(FuzzRegressions, SceneSpec) {
  EXPECT_GT(replay("scene_spec", [](const std::uint8_t* d, std::size_t s) { raylab::fuzz::scene_spec(d, s); }), 0u);
}

TEST(FuzzRegressions, SceneImport) {
  EXPECT_GT(replay("scene_import", [](const std::uint8_t* d, std::size_t s) { raylab::fuzz::scene_import(d, s); }), 0u);
}

TEST(FuzzRegressions, RayFile) {
  EXPECT_GT(replay("ray_file", [](const std::uint8_t* d, std::size_t s) { raylab::fuzz::ray_file(d, s); }), 0u);
}

TEST(FuzzRegressions, BuildAndTrace) {
  EXPECT_GT(replay("build_trace", [](const std::uint8_t* d, std::size_t s) { raylab::fuzz::build_and_trace(d, s); }), 0u);
}

// The scene_spec target skips specs above its size budget; the bound it uses must hold, or a
// spec that is too large for the sanitizers' time limit slips through (CI: `subdivided:levels=2`
// of the default bunny, 1.2M triangles, 22 s under ASan).
TEST(FuzzRegressions, SceneSpecSizeBoundHoldsForEveryKind) {
  const std::vector<std::string> specs = {
      "sphere", "sphere:n=8", "sphereflake", "sphereflake:depth=2,as=triangles,tess=5", "stadium",
      "stadium:object=(grass:blades=7),segments=9,tiers=3", "grass", "walls", "room:of=(sphere:n=100),margin=2",
      "soup", "dust", "dust:n=3,size=0.5",
      "needles", "needles:n=7", "fan", "fan:n=3", "row", "row:n=5,gap=0.01", "subdivided:of=(sphere:n=100),levels=2",
      "subdivided:levels=0", "instances", "instances:of=(walls:n=2),count=5", "transformed:of=(sphere:n=100),scale=2",
      "transformed:of=(instances:of=(walls:n=2),count=5),rotate=x:30,translate=1e5:0:0"};
  // Every kind the fuzzer may build (all but meshes by name or path, and decimation) is checked.
  for (const auto& kind : raylab::scene_kinds()) {
    if (kind.name == "cgal" || kind.name == "file" || kind.name == "decimated") continue;
    EXPECT_TRUE(std::any_of(specs.begin(), specs.end(), [&](const std::string& s) { return s.rfind(kind.name, 0) == 0; }))
        << "no spec of kind " << kind.name;
  }
  for (const std::string& spec : specs) {
    SCOPED_TRACE(spec);
    const auto scene = raylab::make_scene(spec);
    double stored = double(scene->primitive_count() + scene->instances.size());
    for (const auto& base : scene->bases) stored += double(base->primitive_count());
    EXPECT_GE(raylab::fuzz::spec_size_bound(spec), stored);
  }
}

TEST(FuzzRegressions, SceneSpecSkipsLargeSpecs) {
  for (const std::string spec : {"subdivided:levels=2", "subdivided:levels=(2)", "subdivided:levels=1",
                                 "sphereflake:depth=(7)", "soup:n=2000000", "instances:of=(sphere:n=8),count=1000000",
                                 "stadium:object=(subdivided:of=(sphere:n=5000),levels=2)"})
    EXPECT_FALSE(raylab::fuzz::small_spec(spec)) << spec;
  for (const std::string spec : {"subdivided:of=(sphere:n=8),levels=1", "instances", "sphereflake:depth=3"})
    EXPECT_TRUE(raylab::fuzz::small_spec(spec)) << spec;
}
