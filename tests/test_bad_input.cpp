// Bad input (issue 6): every loader, the ray-file reader and the scene-spec parser reject bad
// input with one line naming the file (or spec), the line or element and the fault, and the
// `raylab` tool turns it into `raylab: error: ...` and exit status 2. Extends the malformed-mesh
// corpus of tests/data/malformed (test_scene_loaders.cpp) with tests/data/bad_input/: count
// overflows, negative counts, 10^8-vertex headers on tiny files, non-finite values in every
// format, NUL bytes, binary garbage, bad ray files; and runs both corpora through the tool.
// Huge header counts must fail fast: the tool runs them under a 1 GiB address-space limit.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scene_test_files.h"
#include "geometry/input_error.h"
#include "rays/ray_file.h"
#include "scene/mesh_io.h"
#include "scene/procedural.h"
#include "scene/scene_spec.h"

namespace fs = std::filesystem;
using namespace raylab;

namespace {

const fs::path kData = RAYLAB_TEST_DATA;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct ToolRun {
  int status = -1;
  std::string err;
  double seconds = 0;
};

/// Runs the raylab tool with `args`; `limit_kib` > 0 caps its address space (ulimit -v).
ToolRun run_tool(const std::string& args, long limit_kib = 0) {
  const fs::path err = fs::temp_directory_path() / ("raylab_bad_input_" + std::to_string(::getpid()) + ".err");
  std::string cmd = std::string(RAYLAB_TOOL_PATH) + " " + args + " >/dev/null 2>" + err.string() + " </dev/null";
  if (limit_kib > 0) cmd = "ulimit -v " + std::to_string(limit_kib) + "; " + cmd;
  const auto start = std::chrono::steady_clock::now();
  const int raw = std::system(("/bin/sh -c " + shell_quote(cmd)).c_str());
  ToolRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::ifstream in(err);
  std::stringstream s;
  s << in.rdbuf();
  r.err = s.str();
  fs::remove(err);
  return r;
}

void expect_one_error_line(const ToolRun& r, const std::string& what, const std::string& must_name) {
  EXPECT_EQ(r.status, 2) << what << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("raylab: error: ", 0), 0u) << what << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_NE(r.err.find(must_name), std::string::npos) << what << ": the message does not name '" << must_name
                                                      << "': " << r.err;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(BadInput, EveryMeshOfTheCorpusFailsWithOneLineNamingFileAndFault) {
  const auto files = files_in(kData / "bad_input" / "meshes");
  EXPECT_GE(files.size(), 30u);
  for (const auto& f : files) {
    const std::string msg = error_of([&] { load_mesh(f.string()); });
    EXPECT_NE(msg, "") << f << " was accepted";
    EXPECT_NE(msg.find(f.filename().string()), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    // The file name is followed by a fault, not by nothing.
    EXPECT_GT(msg.size(), f.string().size() + 4) << msg;
  }
}

TEST(BadInput, MessagesNameTheElementAndTheFault) {
  auto message = [](const std::string& name) { return error_of([&] { load_mesh((kData / "bad_input" / "meshes" / name).string()); }); };
  EXPECT_NE(message("obj_inf.obj").find(":3:"), std::string::npos) << message("obj_inf.obj");
  EXPECT_NE(message("obj_inf.obj").find("non-finite"), std::string::npos) << message("obj_inf.obj");
  EXPECT_NE(message("ply_inf.ply").find("non-finite"), std::string::npos) << message("ply_inf.ply");
  EXPECT_NE(message("stl_ascii_inf.stl").find("non-finite"), std::string::npos) << message("stl_ascii_inf.stl");
  EXPECT_NE(message("stl_binary_inf.stl").find("non-finite"), std::string::npos) << message("stl_binary_inf.stl");
  EXPECT_NE(message("ply_binary_nan.ply").find("non-finite"), std::string::npos) << message("ply_binary_nan.ply");
}

TEST(BadInput, HugeHeaderCountsFailFastWithoutAllocating) {
  for (const char* name : {"off_100m_vertices.off", "off_face_count_huge.off", "ply_100m_vertices_binary.ply",
                           "off_huge_corner_list.off"}) {
    const auto start = std::chrono::steady_clock::now();
    const std::string msg = error_of([&] { load_mesh((kData / "bad_input" / "meshes" / name).string()); });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_NE(msg, "") << name;
    EXPECT_LT(s, 2.0) << name << " took " << s << " s to reject";
  }
}

TEST(BadInput, EveryBadRayFileFailsWithOneLineNamingFileAndLine) {
  const auto files = files_in(kData / "bad_input" / "rays");
  EXPECT_GE(files.size(), 10u);
  for (const auto& f : files) {
    const std::string msg = error_of([&] { read_rays(f.string()); });
    EXPECT_EQ(msg.rfind(f.string() + ":", 0), 0u) << f << ": '" << msg << "'";
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

/// Both mesh corpora through the tool: `raylab info FILE` prints one error line naming the file
/// and exits 2, under a 1 GiB address-space cap (so a loader that trusted a header count of
/// 10^8 or 4·10^9 would die instead of failing cleanly). ASan reserves terabytes of address
/// space, so the cap is left out in sanitized builds.
TEST(BadInputTool, EveryBadMeshThroughTheTool) {
  const long limit = kAddressSanitizer ? 0 : 1L << 20;  // KiB: 1 GiB
  std::size_t n = 0;
  for (const auto& dir : {kData / "malformed", kData / "bad_input" / "meshes"})
    for (const auto& f : files_in(dir)) {
      const ToolRun r = run_tool("info " + shell_quote(f.string()), limit);
      expect_one_error_line(r, f.string(), f.filename().string());
      ++n;
    }
  EXPECT_GE(n, 90u);
}

/// Bad scene files of the formats Assimp reads (written by the tests: scene_test_files.h) through
/// the tool, under the same address-space cap.
TEST(BadInputTool, EveryBadSceneFileThroughTheTool) {
  const long limit = kAddressSanitizer ? 0 : 1L << 20;  // KiB: 1 GiB
  const fs::path dir = fs::temp_directory_path() / ("raylab_bad_scenes_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const auto& f : test::write_bad_scene_files(dir.string())) {
    const ToolRun r = run_tool("info " + shell_quote(f.path), limit);
    expect_one_error_line(r, f.path, fs::path(f.path).filename().string());
    EXPECT_NE(r.err.find(f.fault), std::string::npos) << r.err;
  }
  fs::remove_all(dir);
}

TEST(BadInputTool, EveryBadRayFileThroughTheTool) {
  for (const auto& f : files_in(kData / "bad_input" / "rays")) {
    const ToolRun r = run_tool("trace --scene sphere:n=64 --accel brute --rays " + shell_quote("file:" + f.string()));
    expect_one_error_line(r, f.string(), f.filename().string());
  }
}

/// Scene specs: unknown kinds and parameters, malformed values, out-of-range and non-finite
/// numbers, unbalanced and deeply nested parentheses, empty scenes. Each fails with one line
/// naming the spec (make_scene and the tool alike).
const std::vector<std::string> kBadSpecs = {
    "",
    ":",
    "no_such_scene",
    "sphere:no_such_param=3",
    "sphere:n=",
    "sphere:n",
    "sphere:=3",
    "sphere:n=5,n=6",
    "sphere:n=abc",
    "sphere:n=1e99",
    "sphere:n=-8",
    "sphere:n=99999999999999999999999",
    "sphere:n=nan",
    "sphere:radius=nan",
    "sphere:radius=inf",
    "sphere:radius=-inf",
    "sphere:radius=0",
    "soup:n=0",
    "soup:n=10,seed=-1",
    "soup:n=10,size=nan",
    "grass:blades=0",
    "walls:n=5,angle=nan",
    "sphereflake:depth=99",
    "sphereflake:depth=1,as=cubes",
    "stadium:object=(soup:n=10",
    "stadium:object=soup:n=10),ratio=5",
    "stadium:object=(no_such_scene)",
    "stadium:object=(sphere:n=8),ratio=nan",
    "instances:of=(soup:n=10),count=0",
    "instances:of=(soup:n=10),count=99999999999",
    "instances:of=(soup:n=0),count=2",
    "subdivided:of=(sphere:n=8),levels=99",
    "subdivided:of=(sphere:n=8),levels=-1",
    "subdivided:of=cgal:bunny00,levels=12",
    "soup:n=-3",
    "grass:blades=-4",
    "instances:of=(soup:n=10),count=-2",
    "decimated:of=(sphere:n=100),faces=-5",
    "subdivided:of=(sphereflake:depth=1),levels=1",
    "decimated:of=(sphere:n=100),faces=0",
    "file:/no/such/file.off",
    "file:",
    "/no/such/mesh.ply",
    "cgal:no_such_mesh",
    "cgal:../../etc/passwd",
};

TEST(BadInput, SceneSpecsFailWithOneLineNamingTheSpec) {
  for (const auto& spec : kBadSpecs) {
    const std::string msg = error_of([&] { make_scene(spec); });
    EXPECT_NE(msg, "") << "'" << spec << "' was accepted";
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    if (!spec.empty()) {
      EXPECT_NE(msg.find(spec.substr(0, std::min<std::size_t>(spec.size(), 6))), std::string::npos)
          << "'" << spec << "': " << msg;
    }
  }
}

/// A spec nested deeper than any scene needs (16 levels) fails at once, with a short message,
/// instead of recursing for minutes (3000 levels) or running out of memory (10^5 levels).
TEST(BadInput, DeeplyNestedSpecsFailCleanly) {
  for (int depth : {17, 64, 100000}) {
    const auto start = std::chrono::steady_clock::now();
    std::string spec;
    for (int i = 0; i < depth; ++i) spec += "stadium:object=(";
    spec += "sphere:n=8";
    for (int i = 0; i < depth; ++i) spec += ")";
    const std::string msg = error_of([&] { make_scene(spec); });
    EXPECT_NE(msg, "") << "depth " << depth;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    EXPECT_LT(msg.size(), 2000u) << "the message should not repeat a huge spec";
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0) << depth;
  }
}

TEST(BadInputTool, SceneSpecsThroughTheTool) {
  for (const auto& spec : kBadSpecs) {
    if (spec.empty()) continue;
    const ToolRun r = run_tool("info " + shell_quote(spec));
    expect_one_error_line(r, spec, spec.substr(0, std::min<std::size_t>(spec.size(), 6)));
  }
}

/// Loop subdivision past the limit (issue 29): the triangle count is estimated (x4 per level)
/// and refused on one line naming the count and the limit, before anything is allocated (the
/// tool runs under the 1 GiB address-space cap; the result would need about 10^14 bytes).
TEST(BadInput, SubdivisionPastTheLimitIsRefusedBeforeAllocating) {
  const std::size_t bunny = make_scene("cgal:bunny00")->mesh.size();
  const std::string spec = "subdivided:of=cgal:bunny00,levels=12";
  const std::string msg = error_of([&] { make_scene(spec); });
  EXPECT_NE(msg.find(std::to_string(bunny) + " triangles would make " + std::to_string(std::uint64_t{bunny} << 24)), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("more than the limit of " + std::to_string(subdivision_triangle_limit()) + " triangles"), std::string::npos) << msg;
  EXPECT_LE(subdivision_triangle_limit(), std::uint64_t{1} << 27);
  EXPECT_GT(subdivision_triangle_limit(), std::uint64_t{1} << 20);
  const long limit = kAddressSanitizer ? 0 : 1L << 20;  // KiB: 1 GiB
  const ToolRun r = run_tool("info " + spec, limit);
  expect_one_error_line(r, spec, "more than the limit of");
  EXPECT_LT(r.seconds, 20.0);
  // Within the limit it subdivides: 8·4^2 triangles.
  EXPECT_EQ(make_scene("subdivided:of=(soup:n=8),levels=2")->mesh.size(), 128u);
}

/// A bad accelerator parameter value is refused before the scene is loaded: on a scene of 4·10^7
/// spheres' triangles (gigabytes) under a 1 GiB address-space limit, one error line naming it, at
/// once (validate_accelerator_spec, the one check of the tool and the sweep plans).
TEST(BadInputTool, ABadAcceleratorValueIsRefusedBeforeTheSceneIsLoaded) {
  const long limit = kAddressSanitizer ? 0 : 1L << 20;  // KiB: 1 GiB
  for (const std::string& accel : {"kdtree:c_isect=nan", "bvh:width=3", "grid:d=1000", "bvh:robust=off,kernel=certified",
                                   "kdtree:cost=default,c_trav=2"}) {
    for (const std::string command : {"trace", "render --out /tmp/raylab_bad_accel.png"}) {
      const std::string args = command + " --scene sphere:n=40000000 --accel " + accel;
      const ToolRun r = run_tool(args, limit);
      expect_one_error_line(r, args, accel.substr(accel.find(':') + 1, 4));
      EXPECT_LT(r.seconds, 20.0) << args;
    }
  }
}

/// A negative count, wherever a count is given (scene and ray specs, --threads, --width,
/// --passes, sweep shards, merge shards), is refused on one line naming it.
TEST(BadInputTool, NegativeCountsGiveOneErrorLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"trace --scene soup:n=-3", "n=-3"},
      {"trace --scene sphere:n=64 --rays diffuse:-5", "-5"},
      {"trace --scene sphere:n=64 --rays shadow:-1", "-1"},
      {"trace --scene sphere:n=64 --threads -1", "--threads -1"},
      {"render --scene sphere:n=64 --out /tmp/raylab_negative_threads.png --threads -1", "--threads -1"},
      {"render --scene sphere:n=64 --out /tmp/raylab_negative_width.png --width -5", "--width"},
      {"sweep --plan quick --check --threads -1", "--threads -1"},
      {"sweep --plan quick --check --passes -1", "--passes -1"},
      {"sweep --plan quick --check --shard -1/2", "-1/2"},
      {"sweep --plan quick --check --shard 1/-2", "1/-2"},
      {"merge --plan quick --shards -1 --out /tmp/raylab_negative_merge.csv /tmp/raylab_negative_shard.csv", "--shards"},
      {"predict --scene sphere:n=64 --accel bvh --threads -1", "--threads -1"},
      {"trace --scene sphere:n=64 --accel bvh:optimize_passes=-1", "optimize_passes"},
      {"trace --scene sphere:n=64 --accel bvh:optimize_budget=-1", "optimize_budget"},
      {"trace --scene sphere:n=64 --accel bvh:optimize=treelet", "optimize"},
      {"trace --scene sphere:n=64 --accel bvh:nodes=compressed", "nodes"},
      {"trace --scene sphere:n=64 --accel bvh:nodes=quantized,width=2", "nodes=quantized"},
      {"trace --scene sphere:n=64 --accel bvh:leaves=indexed,width=2", "leaves=indexed"},
      {"trace --scene sphere:n=64 --accel bvh:leaves=copied", "leaves"},
  };
  fs::remove("/tmp/raylab_negative_threads.png");
  fs::remove("/tmp/raylab_negative_merge.csv");
  for (const auto& [args, name] : cases) {
    const ToolRun r = run_tool(args);
    expect_one_error_line(r, args, name);
  }
  EXPECT_FALSE(fs::exists("/tmp/raylab_negative_threads.png"));
  EXPECT_FALSE(fs::exists("/tmp/raylab_negative_merge.csv"));
}
