// raylab merge (lib/cost/merge.h): shard files become one data set only when every case of the
// plan is there exactly once; a missing shard is reported by its index, duplicates by file and
// line, a row of another plan by file and line, and in each case nothing is written. (That merged
// shards of a real sweep equal the unsharded run is CostSweep.ShardsMergeToTheUnshardedDataSet.)
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cost/merge.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("raylab_merge_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

/// 3 scenes x 2 accels x 2 rays = 12 cases. Merging checks keys only, so no case is measured.
SweepPlan plan12() {
  SweepPlan p;
  p.source = "plan12";
  p.scenes = {"sphere:n=100", "soup:n=50", "walls:n=4,angle=10"};
  p.accels = {"bvh", "kdtree"};
  p.rays = {"primary:64", "shadow:64"};
  return p;
}

RunRecord row_of(const SweepPlan& plan, std::int64_t c) {
  const SweepCase k = plan.case_at(c);
  RunRecord r;
  r.case_number = c;
  r.scene = k.scene;
  r.accel = k.accel;
  r.rays = k.rays;
  r.replicate = k.replicate;
  r.host = "node" + std::to_string(c % 3);
  r.cpu_model = "test CPU";
  r.ns_per_ray_min = 10.0 + static_cast<double>(c) / 7.0;  // a value that must survive the merge to the last bit
  return r;
}

/// Writes shard K of N of `plan` as `raylab sweep --shard K/N` would, less the cases in `skip`.
std::string write_shard(const SweepPlan& plan, std::int64_t k, std::int64_t n, const std::vector<std::int64_t>& skip = {},
                        const std::string& tail = "") {
  const std::string path = scratch("shard-" + std::to_string(k) + "-of-" + std::to_string(n) + ".csv").string();
  std::ofstream out(path, std::ios::trunc | std::ios::binary);
  out << runs_csv_header() << '\n';
  for (std::int64_t c = k; c < plan.case_count(); c += n)
    if (std::find(skip.begin(), skip.end(), c) == skip.end()) out << to_csv_row(row_of(plan, c)) << '\n';
  out << tail;
  return path;
}

MergeOptions options_for(const std::vector<std::string>& files, std::int64_t n, const std::string& out_name) {
  MergeOptions o;
  o.shard_files = files;
  o.shard_count = n;
  o.out = scratch(out_name).string();
  fs::remove(o.out);
  fs::remove(merge_record_path(o.out));
  o.note = "test: 4 shards";
  return o;
}

TEST(CostMerge, CompleteShardsMergeSortedByCaseWithARecordOfHowTheyRan) {
  const SweepPlan plan = plan12();
  std::vector<std::string> files;
  for (int k = 3; k >= 0; --k) files.push_back(write_shard(plan, k, 4));  // any order
  const MergeOptions o = options_for(files, 4, "complete.csv");
  const MergeResult r = merge_shards(plan, o);
  EXPECT_TRUE(r.complete());
  const std::vector<RunRecord> rows = read_runs_csv(o.out);
  ASSERT_EQ(rows.size(), 12u);
  for (std::int64_t c = 0; c < 12; ++c)
    EXPECT_EQ(to_csv_row(rows[static_cast<std::size_t>(c)]), to_csv_row(row_of(plan, c))) << "case " << c;

  std::ifstream in(merge_record_path(o.out));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("format"), "raylab-sweep-merge");
  EXPECT_EQ(j.at("rows"), 12);
  EXPECT_EQ(j.at("cases"), 12);
  EXPECT_EQ(j.at("shards"), 4);
  EXPECT_EQ(j.at("how"), "test: 4 shards");
  EXPECT_EQ(j.at("hosts").size(), 3u);
  EXPECT_EQ(j.at("shard_files").size(), 4u);

  // A second merge into the same data set is refused, and leaves it as it was.
  const auto size = fs::file_size(o.out);
  EXPECT_THROW(merge_shards(plan, o), InputError);
  EXPECT_EQ(fs::file_size(o.out), size);
}

TEST(CostMerge, AHostNameThatIsNotUtf8IsReplacedInTheRecord) {
  const SweepPlan plan = plan12();
  const std::string path = scratch("latin1.csv").string();
  {
    std::ofstream out(path, std::ios::trunc | std::ios::binary);
    out << runs_csv_header() << '\n';
    for (std::int64_t c = 0; c < plan.case_count(); ++c) {
      RunRecord r = row_of(plan, c);
      r.host = "n\xf6" "de";  // Latin-1
      out << to_csv_row(r) << '\n';
    }
  }
  const MergeOptions o = options_for({path}, 1, "latin1_merged.csv");
  merge_shards(plan, o);
  std::ifstream in(merge_record_path(o.out));
  EXPECT_EQ(nlohmann::json::parse(in).at("hosts").at(0), "n\xef\xbf\xbd" "de");  // U+FFFD
  EXPECT_EQ(read_runs_csv(o.out).at(3).host, "n\xf6" "de");  // the data set keeps the bytes
}

TEST(CostMerge, AMissingShardIsReportedByIndexAndNothingIsWritten) {
  const SweepPlan plan = plan12();
  // Shard 2 never ran (no file); shard 1 was killed after its first case, mid-way through a row.
  const std::vector<std::string> files = {write_shard(plan, 0, 4), write_shard(plan, 1, 4, {5, 9}, "5,sphere:n=1"),
                                          scratch("no-such-shard.csv").string(), write_shard(plan, 3, 4)};
  const MergeOptions o = options_for(files, 4, "incomplete.csv");
  try {
    merge_shards(plan, o);
    ADD_FAILURE() << "an incomplete merge was written";
  } catch (const IncompleteMerge& e) {
    EXPECT_EQ(e.result.incomplete_shards, (std::vector<std::int64_t>{1, 2}));
    EXPECT_EQ(e.result.missing_cases, (std::vector<std::int64_t>{2, 5, 6, 9, 10}));
    EXPECT_TRUE(e.result.duplicates.empty());
    EXPECT_FALSE(e.result.files[2].exists);
    EXPECT_TRUE(e.result.files[1].torn_tail);
    const std::string what = e.what();
    EXPECT_NE(what.find("5 of 12 cases missing"), std::string::npos) << what;
    EXPECT_NE(what.find("shards 1, 2 of 4"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(o.out));
  EXPECT_FALSE(fs::exists(merge_record_path(o.out)));

  // Without --shards the files are the shards: the same report.
  const MergeResult r = collect_shards(plan, files);
  EXPECT_EQ(r.incomplete_shards, (std::vector<std::int64_t>{1, 2}));
}

TEST(CostMerge, DuplicatedCasesAreReportedByFileAndLineAndNothingIsWritten) {
  const SweepPlan plan = plan12();
  // Shards of 2 and of 4 in one merge: cases 0, 4, 8 twice.
  const std::vector<std::string> files = {write_shard(plan, 0, 2), write_shard(plan, 0, 4), write_shard(plan, 1, 2)};
  const MergeOptions o = options_for(files, 2, "duplicates.csv");
  try {
    merge_shards(plan, o);
    ADD_FAILURE() << "a merge with duplicates was written";
  } catch (const IncompleteMerge& e) {
    EXPECT_TRUE(e.result.missing_cases.empty());
    ASSERT_EQ(e.result.duplicates.size(), 3u);
    EXPECT_EQ(e.result.duplicates.at(4), (std::vector<std::string>{files[0] + ":4", files[1] + ":3"}));
    EXPECT_NE(std::string(e.what()).find("3 cases more than once"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(o.out));
  EXPECT_FALSE(fs::exists(merge_record_path(o.out)));
}

TEST(CostMerge, ARowOfAnotherPlanIsRejectedByFileAndLine) {
  SweepPlan other = plan12();
  std::swap(other.rays[0], other.rays[1]);
  const std::string foreign = write_shard(other, 1, 2);
  const std::vector<std::string> files = {write_shard(plan12(), 0, 2), foreign};
  const MergeOptions o = options_for(files, 2, "foreign.csv");
  try {
    merge_shards(plan12(), o);
    ADD_FAILURE() << "a row of another plan was merged";
  } catch (const IncompleteMerge& e) {
    ADD_FAILURE() << e.what();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(foreign + ":2: case 1 is (sphere:n=100, bvh, primary:64)"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(o.out));
  // A case number beyond the plan.
  SweepPlan longer = plan12();
  longer.scenes.push_back("sphere:n=200");
  EXPECT_THROW(collect_shards(plan12(), {write_shard(longer, 0, 1)}), InputError);
}

/// plan12 with cases 1, 6 and 11 measured twice more: cases 12..17 are their replicates.
SweepPlan plan12_with_replicates() {
  SweepPlan p = plan12();
  p.replicated = {1, 6, 11};
  p.replicate_repeats = 2;
  return p;
}

TEST(CostMerge, ReplicatesAreCasesOfThePlanWithTheirFirstMeasurementsKey) {
  const SweepPlan plan = plan12_with_replicates();
  ASSERT_EQ(plan.case_count(), 18);
  for (std::int64_t c = 12; c < 18; ++c) {
    const SweepCase k = plan.case_at(c), first = plan.case_at(plan.replicated[static_cast<std::size_t>((c - 12) % 3)]);
    EXPECT_EQ(k.replicate, (c - 12) / 3 + 1);
    EXPECT_EQ(k.first_case, first.number);
    EXPECT_EQ(k.scene + k.accel + k.rays, first.scene + first.accel + first.rays);
  }
  std::vector<std::string> files;
  for (int k = 0; k < 4; ++k) files.push_back(write_shard(plan, k, 4));
  const MergeOptions o = options_for(files, 4, "replicates.csv");
  EXPECT_TRUE(merge_shards(plan, o).complete());
  const std::vector<RunRecord> rows = read_runs_csv(o.out);
  ASSERT_EQ(rows.size(), 18u);
  for (std::int64_t c = 0; c < 18; ++c) {
    EXPECT_EQ(rows[static_cast<std::size_t>(c)].case_number, c);
    EXPECT_EQ(rows[static_cast<std::size_t>(c)].replicate, plan.case_at(c).replicate);
  }
  // A shard of replicates missing is reported like any other; a replicate row passed off as a first
  // measurement (replicate 0) is not the plan's case.
  EXPECT_EQ(collect_shards(plan, {files[0], files[1], files[3]}, 4).missing_cases,
            (std::vector<std::int64_t>{2, 6, 10, 14}));
  RunRecord wrong = row_of(plan, 13);
  wrong.replicate = 0;
  EXPECT_THROW(check_row_in_plan(plan, wrong, "test"), InputError);
  // The plan without its replicates does not hold cases 12..17.
  EXPECT_THROW(collect_shards(plan12(), {files[0]}, 4), InputError);
}

}  // namespace
}  // namespace raylab
