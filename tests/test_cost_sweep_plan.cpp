// Plans that choose their cases (sweep.h): scene objects with their own accels, family-stratified
// samples, replicates numbered after the primary cases, one-line errors for bad plans; a real
// sweep of a plan with replicates, sharded and merged. Also the cache sizes of provenance.h and the
// runs CSV's optional columns (older data sets stay readable).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "cost/merge.h"
#include "cost/provenance.h"
#include "cost/sweep.h"
#include "cost/tree_features.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("raylab_plan_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::string plan_file(const std::string& text) {
  static int n = 0;
  const std::string p = scratch("plan" + std::to_string(n++) + ".json").string();
  std::ofstream(p, std::ios::trunc) << text;
  return p;
}

const char* kAccels = R"("accels": ["bvh", "bvh:leaf_size=1", "bvh:width=2", "kdtree", "kdtree:builder=median", "grid", "grid:d=1", "octree"])";

TEST(CostPlan, APlanOfPlainListsKeepsItsCaseNumbers) {
  const SweepPlan p = load_plan(plan_file(R"({"scenes": ["sphere:n=10", "soup:n=10"], "accels": ["bvh", "kdtree", "grid"],
                                              "rays": ["primary:4", "diffuse:4"]})"));
  EXPECT_EQ(p.case_count(), 12);
  EXPECT_EQ(p.primary_case_count(), 12);
  for (std::int64_t c = 0; c < 12; ++c) {
    const SweepCase k = p.case_at(c);
    EXPECT_EQ(k.scene, p.scenes[static_cast<std::size_t>(c / 6)]);
    EXPECT_EQ(k.accel, p.accels[static_cast<std::size_t>(c / 2 % 3)]);
    EXPECT_EQ(k.rays, p.rays[static_cast<std::size_t>(c % 2)]);
    EXPECT_EQ(k.replicate, 0);
  }
  EXPECT_EQ(p.describe(), "12 cases = 2 scenes x 3 accels x 2 rays");
}

TEST(CostPlan, AScenesAccelsAreItsListOrAStratifiedDeterministicSample) {
  const std::string text = std::string(R"({"scenes": ["sphere:n=10",
      {"scene": "soup:n=10", "accels": ["grid", "bvh"]},
      {"scene": "walls:n=3", "accels": 4}], )") + kAccels + R"(, "rays": ["primary:4", "shadow:4"]})";
  const SweepPlan p = load_plan(plan_file(text));
  EXPECT_EQ(p.accels_of(0).size(), 8u);
  EXPECT_EQ(p.accels_of(1), (std::vector<std::size_t>{0, 5}));  // the plan's order
  ASSERT_EQ(p.accels_of(2).size(), 4u);
  std::set<std::string> families;
  for (std::size_t a : p.accels_of(2)) families.insert(structure_family(p.accels[a]));
  EXPECT_EQ(families.size(), 4u);  // bvh8, bvh, kdtree, grid, octree: four different ones
  EXPECT_EQ(p.primary_case_count(), (8 + 2 + 4) * 2);
  // Cases run scene by scene, each scene's accels in the plan's order, rays fastest.
  EXPECT_EQ(p.case_at(16).scene, "soup:n=10");
  EXPECT_EQ(p.case_at(16).accel, "bvh");
  EXPECT_EQ(p.case_at(19).accel, "grid");
  EXPECT_EQ(p.case_at(19).rays, "shadow:4");
  EXPECT_EQ(p.case_at(20).scene, "walls:n=3");
  EXPECT_EQ(p.describe(), "28 cases = 3 scenes x 2..8 of 8 accels x 2 rays");
  // The same plan samples the same accels; another seed or scene may not, but stays stratified.
  EXPECT_EQ(load_plan(plan_file(text)).accels_of(2), p.accels_of(2));
  const auto six = sample_accels(p.accels, "walls:n=3", 6, 1);
  std::set<std::string> six_families;
  for (std::size_t a : six) six_families.insert(structure_family(p.accels[a]));
  EXPECT_EQ(six_families.size(), 5u);  // every family before any family's second
  EXPECT_TRUE(std::is_sorted(six.begin(), six.end()));
  // accels_per_scene samples every scene given as a string.
  const SweepPlan q = load_plan(plan_file(std::string(R"({"scenes": ["sphere:n=10", "soup:n=10"], "accels_per_scene": 3, )") +
                                          kAccels + R"(, "rays": ["primary:4"]})"));
  EXPECT_EQ(q.case_count(), 6);
}

TEST(CostPlan, ReplicatesCoverAtLeastTheFractionAndEveryFamilyAndComeLast) {
  const SweepPlan p = load_plan(plan_file(std::string(R"({"scenes": ["sphere:n=10", "soup:n=10", "grass:blades=10",
      {"scene": "walls:n=3", "accels": ["octree"]}], )") + kAccels +
                                          R"(, "rays": ["primary:4", "shadow:4", "diffuse:4"], "replicates": {"fraction": 0.1}})"));
  const std::int64_t primary = p.primary_case_count();
  EXPECT_EQ(primary, (3 * 8 + 1) * 3);
  const std::int64_t replicates = p.case_count() - primary;
  EXPECT_GE(replicates, (primary + 9) / 10);
  std::set<std::string> accel_families, scene_families;
  std::set<std::int64_t> firsts;
  for (std::int64_t c = primary; c < p.case_count(); ++c) {
    const SweepCase k = p.case_at(c), first = p.case_at(k.first_case);
    EXPECT_EQ(k.replicate, 1);
    EXPECT_LT(k.first_case, primary);
    EXPECT_TRUE(firsts.insert(k.first_case).second);
    EXPECT_EQ(k.scene + k.accel + k.rays, first.scene + first.accel + first.rays);
    accel_families.insert(structure_family(k.accel));
    scene_families.insert(scene_family_of(k.scene));
  }
  EXPECT_EQ(accel_families.size(), 5u);
  EXPECT_EQ(scene_families.size(), 4u);  // walls only through its one octree
  // repeats: each replicated case R times, all first repeats before the second ones.
  const SweepPlan twice = load_plan(plan_file(std::string(R"({"scenes": ["sphere:n=10"], )") + kAccels +
                                              R"(, "rays": ["primary:4"], "replicates": {"fraction": 0.25, "repeats": 2}})"));
  EXPECT_EQ(twice.case_count(), 8 + 2 * static_cast<std::int64_t>(twice.replicated.size()));
  EXPECT_EQ(twice.case_at(8 + static_cast<std::int64_t>(twice.replicated.size())).replicate, 2);
  EXPECT_THROW(twice.case_at(twice.case_count()), std::out_of_range);
}

TEST(CostPlan, BadPlanKeysGiveOneLineErrors) {
  const std::string rays = R"("rays": ["primary:4"])";
  const std::pair<std::string, std::string> bad[] = {
      {R"({"scenes": [{"scene": "soup:n=10", "acels": 2}], "accels": ["bvh"], )" + rays + "}", "unknown key 'acels'"},
      {R"({"scenes": [{"accels": 1}], "accels": ["bvh"], )" + rays + "}", "expected \"scene\""},
      {R"({"scenes": [{"scene": "soup:n=10", "accels": ["grid"]}], "accels": ["bvh"], )" + rays + "}",
       "scenes[0]: accels[0]: expected one of the plan's accels"},
      {R"({"scenes": [{"scene": "soup:n=10", "accels": 3}], "accels": ["bvh"], )" + rays + "}", "expected an integer in [1, 1]"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "accels_per_scene": 0, )" + rays + "}", "accels_per_scene"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "replicates": {"fraction": 0}, )" + rays + "}", "fraction"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "replicates": {"fraction": 0.1, "every": 3}, )" + rays + "}",
       "unknown key 'every'"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "sample_seed": -1, )" + rays + "}", "sample_seed"},
      {R"({"scenes": ["soup:n=10", {"scene": "soup:n=10"}], "accels": ["bvh"], )" + rays + "}", "listed twice"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "seconds_per_case": 0, )" + rays + "}", "seconds_per_case"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "seconds_per_case": 11, )" + rays + "}", "seconds_per_case"},
      {R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "seconds_per_case": "0.1", )" + rays + "}", "seconds_per_case"},
  };
  for (const auto& [text, expected] : bad) {
    try {
      load_plan(plan_file(text));
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(expected), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
}

TEST(CostPlan, ItsSecondsPerCaseSetHowLongEachCaseIsTimed) {
  const auto passes = [](const std::string& seconds) {
    const SweepPlan plan = load_plan(plan_file(R"({"scenes": ["sphere:n=64"], "accels": ["bvh"], "rays": ["primary:16"])" +
                                               seconds + "}"));
    SweepOptions o;
    o.out = scratch("seconds_per_case.csv").string();
    o.timing.min_seconds = 0;
    fs::remove(o.out);
    run_sweep(plan, o);
    const std::vector<RunRecord> rows = read_runs_csv(o.out);
    return rows.empty() ? 0 : rows.front().passes;
  };
  EXPECT_EQ(passes(""), TimingOptions{}.min_passes);  // the options' 0 s: the fewest passes
  EXPECT_GT(passes(R"(, "seconds_per_case": 0.02)"), TimingOptions{}.min_passes);  // 16 rays take ~1 µs
}

TEST(CostPlan, TheShippedPlansSpanTheirScaleWithReplicates) {
  for (const char* name : {"quick", "full"}) {
    const SweepPlan p = load_plan(name);
    EXPECT_GE(static_cast<double>(p.case_count() - p.primary_case_count()), 0.1 * static_cast<double>(p.primary_case_count()))
        << name;
    std::set<std::string> scene_families;
    for (const std::string& s : p.scenes) scene_families.insert(scene_family_of(s));
    for (const char* family : {"cgal", "sphereflake", "grass", "walls", "stadium", "soup"})
      EXPECT_TRUE(scene_families.count(family)) << name << " lacks " << family;
  }
}

/// A plan with replicates, measured: sharded runs merge to the unsharded one, replicates included.
TEST(CostPlan, APlanWithReplicatesSweepsShardsAndMerges) {
  const SweepPlan plan = load_plan(plan_file(R"({"scenes": ["sphere:n=300", {"scene": "walls:n=8,angle=20", "accels": ["grid"]}],
      "accels": ["bvh", "kdtree", "grid"], "rays": ["primary:512", "shadow:256"], "replicates": {"fraction": 0.25}})"));
  ASSERT_GT(plan.case_count(), plan.primary_case_count());
  auto sweep_into = [&](const std::string& name, ShardSpec shard) {
    SweepOptions o;
    o.out = scratch(name).string();
    o.shard = shard;
    o.timing.min_seconds = 0;
    fs::remove(o.out);
    run_sweep(plan, o);
    return o.out;
  };
  const std::vector<RunRecord> whole = read_runs_csv(sweep_into("whole.csv", {0, 1}));
  ASSERT_EQ(static_cast<std::int64_t>(whole.size()), plan.case_count());
  MergeOptions m;
  m.shard_files = {sweep_into("s1.csv", {1, 3}), sweep_into("s0.csv", {0, 3}), sweep_into("s2.csv", {2, 3})};
  m.shard_count = 3;
  m.out = scratch("merged.csv").string();
  fs::remove(m.out);
  fs::remove(merge_record_path(m.out));
  ASSERT_TRUE(merge_shards(plan, m).complete());
  const std::vector<RunRecord> merged = read_runs_csv(m.out);
  ASSERT_EQ(merged.size(), whole.size());
  for (std::size_t i = 0; i < whole.size(); ++i) {
    const SweepCase c = plan.case_at(static_cast<std::int64_t>(i));
    EXPECT_EQ(whole[i].replicate, c.replicate);
    EXPECT_EQ(merged[i].replicate, c.replicate);
    EXPECT_EQ(merged[i].case_number, whole[i].case_number);
    if (c.replicate == 0) continue;
    // A replicate repeats its first measurement's counters and features exactly (the builds and
    // rays are deterministic), with a time of its own.
    const RunRecord& first = whole[static_cast<std::size_t>(c.first_case)];
    EXPECT_EQ(whole[i].nodes_per_ray, first.nodes_per_ray);
    EXPECT_EQ(whole[i].bytes, first.bytes);
    EXPECT_EQ(whole[i].lines_per_ray_est, first.lines_per_ray_est);
    EXPECT_GT(whole[i].ns_per_ray_min, 0);
  }
  // A resumed sweep takes the replicates of a file as the plan's and measures the rest.
  {
    SweepOptions o;
    o.out = sweep_into("resumed.csv", {0, 2});
    o.resume = true;
    o.timing.min_seconds = 0;
    const SweepSummary s = run_sweep(plan, o);
    EXPECT_EQ(s.skipped + s.measured, plan.case_count());
    EXPECT_EQ(static_cast<std::int64_t>(read_runs_csv(o.out).size()), plan.case_count());
  }
  for (const RunRecord& r : whole) {
    EXPECT_GT(r.lines_per_ray_est, 0) << r.accel;
    EXPECT_GT(r.working_set_bytes_est, 0) << r.accel;
    EXPECT_LE(r.working_set_bytes_est, static_cast<double>(r.bytes)) << r.accel;
    EXPECT_FALSE(r.cache_source.empty());
    EXPECT_GT(r.embree_bytes, 0) << r.scene;  // the Embree scene the row was timed against
  }
}

TEST(CostCaches, SysfsSizeStringsParse) {
  EXPECT_EQ(parse_cache_size("48K"), 48 * 1024);
  EXPECT_EQ(parse_cache_size("2048K\n"), 2048 * 1024);
  EXPECT_EQ(parse_cache_size("32M"), std::int64_t{32} << 20);
  EXPECT_EQ(parse_cache_size(" 1G "), std::int64_t{1} << 30);
  EXPECT_EQ(parse_cache_size("3"), 3);
  EXPECT_EQ(parse_cache_size("32m"), std::int64_t{32} << 20);
  for (const char* bad : {"", "K", "48KB", "4 8K", "-1K", "0x10", "48Q", "99999999999999999999K"})
    EXPECT_EQ(parse_cache_size(bad), -1) << bad;
}

TEST(CostCaches, SysfsIsReadAndCheckedAgainstSysconf) {
  const fs::path dir = scratch("cache");
  fs::remove_all(dir);
  auto index = [&](int i, const char* level, const char* type, const char* size) {
    const fs::path d = dir / ("index" + std::to_string(i));
    fs::create_directories(d);
    std::ofstream(d / "level") << level << "\n";
    std::ofstream(d / "type") << type << "\n";
    std::ofstream(d / "size") << size << "\n";
  };
  index(0, "1", "Data", "48K");
  index(1, "1", "Instruction", "32K");
  index(2, "2", "Unified", "2048K");
  index(3, "3", "Unified", "32M");
  const CacheSizes sysfs = read_sysfs_cache_sizes(dir.string());
  EXPECT_EQ(sysfs.l1d, 48 << 10);
  EXPECT_EQ(sysfs.l2, 2048 << 10);
  EXPECT_EQ(sysfs.l3, 32 << 20);
  EXPECT_EQ(sysfs.source, "sysfs");
  CacheSizes sysconf_sizes;
  sysconf_sizes.l1d = 48 << 10;
  sysconf_sizes.l2 = 2048 << 10;
  sysconf_sizes.l3 = 320 << 20;
  sysconf_sizes.source = "sysconf";
  const CacheSizes used = reconcile_cache_sizes(sysfs, sysconf_sizes);
  EXPECT_EQ(used.last_level(), 32 << 20);
  EXPECT_EQ(used.source, "sysfs; sysconf differs: L3 335544320");
  sysconf_sizes.l3 = 32 << 20;
  EXPECT_EQ(reconcile_cache_sizes(sysfs, sysconf_sizes).source, "sysfs");
  // No sysfs (some containers): sysconf's sizes, said so.
  const CacheSizes none = read_sysfs_cache_sizes((dir / "absent").string());
  EXPECT_EQ(none.source, "none");
  EXPECT_EQ(reconcile_cache_sizes(none, sysconf_sizes).source, "sysconf");
  EXPECT_EQ(reconcile_cache_sizes(none, sysconf_sizes).l3, 32 << 20);
}

TEST(CostRunsCsv, OlderDataSetsReadWithTheNewColumnsAtTheirDefaults) {
  // The first 120 rows of the data set the lab committed at 1a5e5a6, before these columns.
  const std::string older = std::string(RAYLAB_TEST_DATA) + "/cost_runs_before_replicates.csv";
  const std::vector<RunRecord> rows = read_runs_csv(older);
  ASSERT_GT(rows.size(), 100u);
  for (const RunRecord& r : rows) {
    EXPECT_EQ(r.replicate, 0);
    EXPECT_EQ(r.cache_source, "");
    EXPECT_EQ(r.lines_per_ray_est, 0.0);
    EXPECT_EQ(r.build_passes, 1);
    EXPECT_EQ(r.ns_per_ray_max, 0.0);  // the slowest pass: not recorded then
    EXPECT_EQ(r.embree_ns_per_ray_max, 0.0);
    EXPECT_EQ(r.build_s_max, 0.0);
    EXPECT_EQ(r.embree_bytes, 0);
  }
  // Rewritten with today's columns, they read back the same.
  const std::string path = scratch("rewritten.csv").string();
  {
    std::ofstream out(path, std::ios::trunc | std::ios::binary);
    out << runs_csv_header() << '\n';
    RunRecord r = rows.front();
    r.replicate = 2;
    r.cache_source = "sysfs; sysconf differs: L3 335544320";
    r.working_set_bytes_est = 1234.5;
    r.build_passes = 3;
    r.ns_per_ray_max = 2.5 * r.ns_per_ray_min;
    r.embree_ns_per_ray_max = 1.5 * r.embree_ns_per_ray_min;
    r.build_s_max = 3 * r.build_s;
    r.embree_bytes = 88 * r.primitives;
    out << to_csv_row(r) << '\n';
  }
  const RunRecord back = read_runs_csv(path).front();
  EXPECT_EQ(back.replicate, 2);
  EXPECT_EQ(back.cache_source, "sysfs; sysconf differs: L3 335544320");
  EXPECT_EQ(back.working_set_bytes_est, 1234.5);
  EXPECT_EQ(back.build_passes, 3);
  EXPECT_EQ(back.ns_per_ray_max, 2.5 * rows.front().ns_per_ray_min);
  EXPECT_EQ(back.ns_per_ray_min, rows.front().ns_per_ray_min);
  EXPECT_EQ(back.embree_ns_per_ray_max, 1.5 * rows.front().embree_ns_per_ray_min);
  EXPECT_EQ(back.build_s_max, 3 * rows.front().build_s);
  EXPECT_EQ(back.embree_bytes, 88 * rows.front().primitives);
}

TEST(CostMemoryFeatures, EstimatesFollowTheirDefinitions) {
  TreeFeatures f;
  f.inner_nodes = 3;
  f.leaves = 1;
  f.bytes = 4 * 129;  // 129 bytes a cell: 3 lines at a random offset
  f.batch_cells = 2.5;
  RunRecord r;
  r.nodes_per_ray = 2;
  r.leaves_per_ray = 1;
  r.l2_bytes = 1 << 10;
  r.llc_bytes = 0;
  fill_memory_features(r, f);
  EXPECT_DOUBLE_EQ(r.lines_per_ray_est, 3 * 3.0);
  EXPECT_DOUBLE_EQ(r.working_set_bytes_est, 2.5 * 129);
  EXPECT_DOUBLE_EQ(r.bytes_over_l2, 4 * 129 / 1024.0);
  EXPECT_EQ(r.bytes_over_llc, 0.0);
  f.batch_cells = 10;  // never more than the structure
  fill_memory_features(r, f);
  EXPECT_DOUBLE_EQ(r.working_set_bytes_est, 4 * 129);
}

}  // namespace
}  // namespace raylab
