// The `raylab` tool as a user runs it: bad input of every kind gives one line
// `raylab: error: ...` on stderr and exit status 2; a good trace prints one JSON object with the
// documented fields, and brute force agrees with the exact oracle.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sched.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "scene_test_files.h"

namespace {

struct ToolRun {
  int status = -1;
  std::string out, err;
};

ToolRun run_tool(const std::string& args) {
  const auto dir = std::filesystem::temp_directory_path() / ("raylab_cli_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "out").string(), err = (dir / "err").string();
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  const std::string cmd = std::string(RAYLAB_TOOL_PATH) + " " + args + " >" + out + " 2>" + err + " </dev/null";
  const int raw = std::system(cmd.c_str());
  ToolRun r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("raylab_cli_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

TEST(ToolCli, BadInputGivesOneErrorLineAndExitStatusTwo) {
  const std::string nan_rays = write_file("nan.rays", "0 0 5 0 0 -1 0 inf\nnan 0 5 0 0 -1 0 inf\n");
  const std::string empty_off = write_file("empty.off", "OFF\n0 0 0\n");
  const std::vector<std::string> cases = {
      "trace --scene cgal:no_such_mesh",
      "trace --scene /no/such/file.off",
      "trace --scene " + empty_off,
      "trace --scene soup:n=100 --accel no-such-accel",
      "trace --scene soup:n=100 --accel embree:quality=ultra",
      "trace --scene soup:n=100 --accel brute:leaf=4",
      "trace --scene soup:n=0",
      "trace --scene soup:n=100 --rays primary:-5",
      "trace --scene soup:n=100 --rays file:" + nan_rays,
      "trace --scene soup:n=100 --check oracle",
      "trace --scene sphere:n=nan",
      "info 'stadium:object=(soup:n=10'",
      "render --scene soup:n=100 --out image.jpg",
      "render --scene soup:n=100 --accel embree --heatmap --out /tmp/raylab_cli_heat.png",
      "trace --scene sphere:n=64 --accel bvh:kernel=certified,robust=off",
      "trace --scene sphere:n=64 --accel grid:kernel=certified,accept=first",
      "trace --scene sphere:n=64 --accel kdtree:kernel=mt",
      "trace --scene transformed:of=sphere,rotate=w:30",
      "trace --scene transformed:of=sphere,translate=1:2",
      "trace --scene transformed:of=sphere,scale=0",
      "trace --scene 'transformed:of=(sphere:radius=1e10),scale=1e30'",
      "trace --scene soup:n=100 --rays touching:10",
      "render --scene soup:n=100 --log --out /tmp/raylab_cli_log.png",
      "render --scene soup:n=100 --camera behind --out /tmp/raylab_cli_camera.png",
  };
  for (const auto& args : cases) {
    const ToolRun r = run_tool(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("raylab: error: ", 0), 0u) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
  }
}

// RAYLAB_TIMING_CPU (accel/common/timing_cpu.h): a CPU the process may use pins the single-thread
// trace; anything else is one error line before any work.
TEST(ToolCli, TimingCpuFromTheEnvironment) {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  int cpu = 0;
  while (!CPU_ISSET(cpu, &mask)) ++cpu;
  for (const std::string& bad : {std::string("x"), std::string("-3"), std::to_string(CPU_SETSIZE)}) {
    setenv("RAYLAB_TIMING_CPU", bad.c_str(), 1);
    const ToolRun r = run_tool("trace --scene soup:n=100 --threads 1");
    EXPECT_EQ(r.status, 2) << bad << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("raylab: error: RAYLAB_TIMING_CPU=" + bad + ": not a CPU this process may run on", 0), 0u)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  setenv("RAYLAB_TIMING_CPU", std::to_string(cpu).c_str(), 1);
  const ToolRun ok = run_tool("trace --scene soup:n=100 --rays diffuse:1000 --threads 1 --json");
  unsetenv("RAYLAB_TIMING_CPU");
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_EQ(nlohmann::json::parse(ok.out)["rays"], 1000);
}

TEST(ToolCli, RenderWritesALogScaleHeatmap) {
  const std::string path = write_file("heat_log.png", "");
  const ToolRun r = run_tool("render --scene fan:n=500 --accel bvh --heatmap --log --width 48 --height 40 --out " + path);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  in.seekg(0, std::ios::end);
  EXPECT_GT(in.tellg(), 200);
}

TEST(ToolCli, TracePrintsOneJsonObjectAndBruteForceMatchesTheOracle) {
  const ToolRun r = run_tool("trace --scene sphere:n=2000 --accel brute --rays diffuse:2000 --threads 1 --check exact --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"scene", "triangles", "accel", "build_s", "rays", "trace_s", "mrays_per_s", "hit_rate",
                          "nodes_per_ray", "leaves_per_ray", "prim_tests_per_ray", "mailbox_skips_per_ray",
                          "accel_bytes", "peak_rss_bytes", "mismatches", "ties"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["rays"], 2000);
  EXPECT_EQ(j["mismatches"], 0);
  EXPECT_EQ(j["threads"], 1);
  EXPECT_DOUBLE_EQ(j["prim_tests_per_ray"].get<double>(), static_cast<double>(j["triangles"].get<int>()));
}

// --check exact counts mismatches per contact class (the exact oracle classifies every ray) and
// judges the certified kernel by the exact rule; --classify writes each ray's class into
// --hits-out; the exact path is counted per ray.
TEST(ToolCli, TraceCountsMismatchesPerContactClass) {
  const std::string hits_path = write_file("classified.csv", "");
  const ToolRun w = run_tool("trace --scene sphere:n=2000 --accel brute:kernel=watertight --rays touching:500 --threads 2 --check exact "
                             "--classify --json --hits-out " + hits_path);
  ASSERT_EQ(w.status, 0) << w.err;
  const auto j = nlohmann::json::parse(w.out);
  for (const char* key : {"mismatches_crossing", "mismatches_touching", "mismatches_on_surface", "ill_conditioned_rays",
                          "rays_touching", "exact_fallbacks_per_ray", "check_rule"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["rays_touching"], 500);
  EXPECT_EQ(j["ill_conditioned_rays"], 500);
  EXPECT_EQ(j["check_rule"], "tolerance");
  EXPECT_GT(j["mismatches_touching"].get<int>(), 0) << "the watertight kernel decides no touching ray wrong?";
  EXPECT_EQ(j["mismatches"], j["mismatches_touching"]);
  // Every touching ray here is ill-conditioned: its bucket, where the watertight kernel claims nothing.
  const auto& ill = j["mismatches_by_bucket"]["ill_conditioned"];
  EXPECT_EQ(ill["rays"], 500);
  EXPECT_EQ(ill["mismatches"], j["mismatches"]);
  EXPECT_EQ(j["mismatches_by_bucket"]["crossing"]["rays"], 0);
  EXPECT_EQ(j["within_stated_bound"], true);
  EXPECT_FALSE(j.contains("bound_exceeded"));
  std::ifstream in(hits_path);
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header, "ray,prim,t,u,v,contact");
  EXPECT_EQ(row.substr(row.rfind(',') + 1), "touching+ill");

  const ToolRun c = run_tool("trace --scene sphere:n=2000 --accel bvh --rays touching:500 --threads 2 "
                             "--check exact --json");
  ASSERT_EQ(c.status, 0) << c.err;
  const auto k = nlohmann::json::parse(c.out);
  EXPECT_EQ(k["check_rule"], "exact");
  EXPECT_EQ(k["mismatches"], 0);
  EXPECT_EQ(k["within_stated_bound"], true);
  EXPECT_DOUBLE_EQ(k["exact_fallbacks_per_ray"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(k["interval_stage_per_ray"].get<double>(), 1.0) << "the exact path is reached through the double stage";
  // trace says which kernel ran and what it guarantees, as `raylab accels` states it.
  EXPECT_EQ(k["kernel"], "certified");
  EXPECT_EQ(k["guarantee"]["exact"], true);
  EXPECT_EQ(k["guarantee"]["max_mismatch_rate"]["touching"], 0.0);
  EXPECT_EQ(j["kernel"], "watertight");
  EXPECT_EQ(j["guarantee"]["rule"], "tolerance");
  EXPECT_EQ(j["guarantee"]["max_mismatch_rate"]["touching"], 1.0);

  // The certified kernel is the default; robust=off rules it out (plain slab test and
  // Moller-Trumbore), grid:accept=first takes the watertight one, and trace names the kernel that
  // ran; Embree runs its own.
  for (const auto& [accel, kernel] : std::vector<std::pair<std::string, std::string>>{
           {"bvh:robust=off", "mt"}, {"grid:accept=first", "watertight"}, {"brute:kernel=mt", "mt"},
           {"kdtree", "certified"}, {"embree", "embree"}}) {
    const ToolRun f = run_tool("trace --scene sphere:n=2000 --accel " + accel + " --rays primary:100 --json");
    ASSERT_EQ(f.status, 0) << f.err;
    EXPECT_EQ(nlohmann::json::parse(f.out)["kernel"], kernel) << accel;
  }

  // `raylab accels` states each bound per class, and the watertight one beside the default.
  const ToolRun a = run_tool("accels");
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NE(a.out.find("max mismatch rate per class (tolerance rule): crossing 0 (edge/vertex-aimed: 0), touching 1"),
            std::string::npos);
  EXPECT_NE(a.out.find("accuracy with kernel=watertight"), std::string::npos);
  EXPECT_NE(a.out.find("(exact rule): crossing 0 (edge/vertex-aimed: 0), touching 0, on_surface 0, ill_conditioned 0"),
            std::string::npos);
}

// Determinism across runs (issue 6): two separate processes build the same structure (its
// hash) and write the same hits, byte for byte, for every builder family.
TEST(ToolCli, SeparateRunsBuildTheSameStructureAndHits) {
  const std::string scene = "soup:n=3000";
  for (const std::string accel : {"bvh", "bvh:builder=spatial", "bvh:builder=sweep,width=2", "kdtree", "octree",
                                  "bsp", "grid"}) {
    std::string hashes[2], hits[2];
    for (int run = 0; run < 2; ++run) {
      const std::string hits_path = write_file("determinism_" + std::to_string(run) + ".csv", "");
      const ToolRun r = run_tool("trace --scene " + scene + " --accel " + accel +
                                 " --rays diffuse:2000 --json --no-counters --hits-out " + hits_path);
      ASSERT_EQ(r.status, 0) << accel << ": " << r.err;
      const auto j = nlohmann::json::parse(r.out);
      ASSERT_TRUE(j.contains("structure_hash")) << accel;
      hashes[run] = j["structure_hash"].get<std::string>();
      std::ifstream in(hits_path);
      std::stringstream text;
      text << in.rdbuf();
      hits[run] = text.str();
    }
    EXPECT_EQ(hashes[0], hashes[1]) << accel;
    EXPECT_FALSE(hits[0].empty()) << accel;
    EXPECT_EQ(hits[0], hits[1]) << accel;
  }
}

TEST(ToolCli, RayFilesRoundTripThroughTrace) {
  const std::string rays = write_file("one.rays", "# one ray down the z axis\n0.25 0.25 5 0 0 -1 0 inf\n");
  const std::string hits = (std::filesystem::temp_directory_path() / "raylab_cli_hits.csv").string();
  const std::string mesh = write_file("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const ToolRun r = run_tool("trace --scene " + mesh + " --accel brute --rays file:" + rays + " --hits-out " + hits + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(hits);
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header, "ray,prim,t,u,v");
  EXPECT_EQ(row.substr(0, 8), "0,0,5,0.");
}

// A glTF scene (issue 20): `info` counts meshes, instances, total and unique triangles;
// `scenes` says which library reads which format; hit files name instance and base.
TEST(ToolCli, GltfSceneInfoFormatsAndHitColumns) {
  raylab::test::GltfDocument doc = raylab::test::shared_cube_document();
  doc.meshes.push_back(raylab::test::unit_cube());
  doc.nodes.push_back(raylab::test::trs_node(1, {0, 3, 0}));
  doc.roots.push_back(2);
  const std::string path = write_file("cubes.gltf", "");
  raylab::test::write_gltf(path, doc);
  const ToolRun info = run_tool("info --json " + path);
  ASSERT_EQ(info.status, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["meshes"], 2);
  EXPECT_EQ(j["instances"], 2);
  EXPECT_EQ(j["triangles"], 36);
  EXPECT_EQ(j["unique_triangles"], 24);
  EXPECT_EQ(j["closed"], true);

  const ToolRun scenes = run_tool("scenes");
  for (const char* line : {".off   OFF", ".stl   STL, ASCII or binary, read by OpenMesh", ".gltf  glTF 2.0",
                           ".glb   glTF 2.0, binary, read by Assimp", ".fbx", ".dae   COLLADA, read by Assimp", ".3ds"})
    EXPECT_NE(scenes.out.find(line), std::string::npos) << line << "\n" << scenes.out;

  const std::string hits = write_file("cubes_hits.csv", "");
  const ToolRun trace = run_tool("trace --scene " + path + " --accel kdtree --rays lines:3000 --no-counters --hits-out " + hits);
  ASSERT_EQ(trace.status, 0) << trace.err;
  std::ifstream in(hits);
  std::string row;
  std::getline(in, row);
  EXPECT_EQ(row, "ray,prim,t,u,v,instance,base");
  std::size_t on_instances = 0, on_flat = 0;
  while (std::getline(in, row)) {
    std::vector<std::string> f;
    std::stringstream fields(row);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 7u) << row;
    if (f[1] == "-1") continue;
    EXPECT_LT(std::stoi(f[1]), 12) << row;
    if (f[5] == "-1") {
      EXPECT_EQ(f[6], "-1") << row;
      ++on_flat;
    } else {
      EXPECT_LT(std::stoi(f[5]), 2) << row;
      EXPECT_EQ(f[6], "0") << row;
      ++on_instances;
    }
  }
  EXPECT_GT(on_instances, 10u);
  EXPECT_GT(on_flat, 5u);
}

}  // namespace
