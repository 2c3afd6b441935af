// `raylab sweep`, `merge`, `fit` and `predict` as a user runs them: bad input gives one error line,
// exit status 2 and no output file; a sweep killed mid-way resumes without losing a row; a merge
// lacking a shard names it on stdout for the lab's scripts; `predict --measure` traces a case as
// the sweep does; `trace --accel auto` says what it chose.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "cost/run_record.h"
#include "cost/sweep.h"

namespace {

namespace fs = std::filesystem;

fs::path scratch_dir() {
  const auto dir = fs::temp_directory_path() / ("raylab_cost_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

struct ToolRun {
  int status = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

ToolRun run_tool(const std::string& args) {
  const auto out = scratch_dir() / "stdout", err = scratch_dir() / "stderr";
  const std::string cmd = std::string(RAYLAB_TOOL_PATH) + " " + args + " >" + out.string() + " 2>" + err.string() + " </dev/null";
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

std::string write_file(const std::string& name, const std::string& text) {
  const auto p = scratch_dir() / name;
  std::ofstream(p, std::ios::trunc) << text;
  return p.string();
}

std::size_t data_rows(const fs::path& csv) {
  const std::string text = slurp(csv);
  const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  return lines > 0 ? lines - 1 : 0;
}

const char* kSmallPlan = R"({"scenes": ["sphere:n=400", "walls:n=10,angle=30"],
  "accels": ["bvh", "bvh:width=2", "kdtree", "grid", "octree"], "rays": ["primary:4096", "diffuse:4096"]})";

/// raylab predict --strict's factor (model_fit.h: kStrictRangeFactor).
constexpr double kStrictFactorForTests = 2.0;

void expect_one_error_line(const ToolRun& r, const std::string& what) {
  EXPECT_EQ(r.status, 2) << what << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("raylab: error: ", 0), 0u) << what << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
}

TEST(CostCli, BadInputGivesOneErrorLineAndNoOutputFile) {
  const std::string plan = write_file("plan.json", kSmallPlan);
  const std::string bad_plan = write_file("bad_plan.json", R"({"scenes": ["sphere:n=10"], "accels": ["embree"], "rays": ["primary:8"]})");
  const std::string not_json = write_file("not_json.json", "{\"scenes\": [");
  const std::string bad_runs = write_file("bad_runs.csv", "case,scene\n0,x\n");
  const std::string header_only = write_file("empty_runs.csv", raylab::runs_csv_header() + "\n");
  const std::string bad_model = write_file("bad_model.json", R"({"format": "raylab-cost-model", "version": 99})");
  const fs::path out = scratch_dir() / "never_written";
  const std::vector<std::string> cases = {
      "sweep --plan /no/such/plan.json --out " + out.string(),
      "sweep --plan " + bad_plan + " --out " + out.string(),
      "sweep --plan " + not_json + " --out " + out.string(),
      "sweep --plan " + plan + " --out " + out.string() + " --shard 3/2",
      "sweep --plan " + plan + " --out " + out.string() + " --shard x",
      "sweep --plan " + plan + " --out " + out.string() + " --passes 2",
      "fit --runs /no/such/runs.csv --out " + out.string(),
      "fit --runs " + bad_runs + " --out " + out.string(),
      "fit --runs " + header_only + " --out " + out.string(),
      "fit --runs " + header_only + " --out " + out.string() + " --target fastest",
      "predict --model " + bad_model + " --scene sphere:n=100 --accel kdtree",
      "predict --model /no/such/model.json --scene sphere:n=100 --accel kdtree",
      "predict --model default --scene sphere:n=100 --accel embree",
      "predict --model default --scene sphere:n=100 --accel kdtree:c_isect=nan",
      "trace --scene sphere:n=100 --accel auto:model=" + bad_model,
      "trace --scene sphere:n=100 --accel kdtree:cost=" + bad_model,
      "trace --scene sphere:n=100 --accel kdtree:cost=default,c_isect=2",
  };
  for (const auto& args : cases) {
    expect_one_error_line(run_tool(args), args);
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}

// cost= on a scene outside the family's fitted range of primitives builds with the fitted constants
// and warns once on stderr, naming the feature and the factor (the model's own range check).
TEST(CostCli, CostOutsideTheFittedRangeWarnsOnceAndBuilds) {
  const ToolRun r = run_tool("trace --scene sphere:n=200 --accel kdtree:cost=default --rays primary:100 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("cost=default: kdtree primitives 224 is"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("below the fitted"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("cost=default", r.err.find("cost=default") + 1), std::string::npos) << "warned twice: " << r.err;
}

TEST(CostCli, ExistingOutputWithoutResumeIsRefusedAndKept) {
  const std::string plan = write_file("plan_keep.json", kSmallPlan);
  const std::string out = write_file("keep.csv", "not a runs file\n");
  expect_one_error_line(run_tool("sweep --plan " + plan + " --out " + out), "existing out");
  EXPECT_EQ(slurp(out), "not a runs file\n");
  expect_one_error_line(run_tool("sweep --plan " + plan + " --out " + out + " --resume"), "resume of a non-runs file");
  EXPECT_EQ(slurp(out), "not a runs file\n");
}

TEST(CostCli, AKilledSweepResumesWithoutLosingARow) {
  const std::string plan = write_file("plan_kill.json", kSmallPlan);
  const fs::path out = scratch_dir() / "killed.csv";
  fs::remove(out);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int devnull = ::open("/dev/null", O_WRONLY);
    dup2(devnull, 2);
    execl(RAYLAB_TOOL_PATH, RAYLAB_TOOL_PATH, "sweep", "--plan", plan.c_str(), "--out", out.c_str(), nullptr);
    _exit(127);
  }
  // Kill it as soon as three rows are on disk.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (data_rows(out) < 3 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the sweep ended before it could be killed";
  const std::string before = slurp(out);
  const std::size_t kept = data_rows(out);
  ASSERT_GE(kept, 3u);

  const ToolRun r = run_tool("sweep --plan " + plan + " --out " + out.string() + " --resume");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<raylab::RunRecord> rows = raylab::read_runs_csv(out.string());
  ASSERT_EQ(rows.size(), 20u);  // 2 scenes x 5 accels x 2 ray sets
  std::vector<bool> seen(20, false);
  for (const auto& row : rows) {
    ASSERT_LT(row.case_number, 20);
    EXPECT_FALSE(seen[static_cast<std::size_t>(row.case_number)]) << "case " << row.case_number << " twice";
    seen[static_cast<std::size_t>(row.case_number)] = true;
  }
  // The rows written before the kill are still there, unchanged (a torn last line aside).
  const std::string after = slurp(out);
  const std::string complete_before = before.substr(0, before.rfind('\n') + 1);
  EXPECT_EQ(after.compare(0, complete_before.size(), complete_before), 0);
}

TEST(CostCli, PredictMeasuresACaseAsTheSweepDoesAndFitPrintsItsConstants) {
  const std::string plan = write_file("plan_predict.json", kSmallPlan);
  const fs::path runs = scratch_dir() / "predict_runs.csv", model = scratch_dir() / "predict_model.json";
  fs::remove(runs);
  fs::remove(model);
  ASSERT_EQ(run_tool("sweep --plan " + plan + " --out " + runs.string()).status, 0);
  const ToolRun fit = run_tool("fit --runs " + runs.string() + " --out " + model.string());
  ASSERT_EQ(fit.status, 0) << fit.err;
  EXPECT_NE(fit.out.find("held-out MAPE"), std::string::npos) << fit.out;
  EXPECT_NE(fit.out.find("±"), std::string::npos) << fit.out;
  EXPECT_NE(fit.out.find("measured C_trav:C_isect"), std::string::npos) << fit.out;
  ASSERT_TRUE(fs::exists(model));

  // Case 5 of the plan: (sphere:n=400, kdtree, diffuse:4096).
  const std::vector<raylab::RunRecord> rows = raylab::read_runs_csv(runs.string());
  const auto row = std::find_if(rows.begin(), rows.end(), [](const auto& r) { return r.case_number == 5; });
  ASSERT_NE(row, rows.end());
  ASSERT_EQ(row->accel, "kdtree");
  const ToolRun p = run_tool("predict --model " + model.string() +
                             " --scene sphere:n=400 --accel kdtree --rays diffuse:4096 --measure --json");
  ASSERT_EQ(p.status, 0) << p.err;
  const auto j = nlohmann::json::parse(p.out);
  for (const char* key : {"predicted_ns_per_ray", "measured_ns_per_ray", "predicted_from_counters_ns_per_ray"})
    EXPECT_GT(j.at(key).get<double>(), 0.0) << key;
  // The same rays through the same tree: the counted pass agrees to the last ray.
  EXPECT_DOUBLE_EQ(j.at("nodes_per_ray").get<double>(), row->nodes_per_ray);
  EXPECT_DOUBLE_EQ(j.at("tests_per_ray").get<double>(), row->tests_per_ray);
  EXPECT_GE(j.at("passes").get<int>(), 5);
  EXPECT_GE(row->passes, 5);
  // The fit printed the held-out coverage of its intervals. This plan gives each family 4 rows, no
  // more than the tree model's terms: no residual spread, so no tree interval (null), but the counters one.
  EXPECT_NE(fit.out.find("90% intervals cover"), std::string::npos) << fit.out;
  EXPECT_NE(fit.out.find("replicate error: n/a"), std::string::npos) << fit.out;
  EXPECT_TRUE(j.contains("interval90_ns_per_ray")) << p.out;
  EXPECT_TRUE(j.at("interval90_from_counters_ns_per_ray").is_array()) << p.out;
  EXPECT_FALSE(j.at("extrapolated").get<bool>());
  EXPECT_TRUE(p.err.empty()) << p.err;

  // A model whose rows bracket the case (jittered copies of its row over six made-up scenes, times
  // from known constants with 5% log-normal noise): the prediction carries a 90% interval.
  const fs::path bracket = scratch_dir() / "bracket_runs.csv", bracket_model = scratch_dir() / "bracket_model.json";
  {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> jitter(0.5, 2.0);
    std::normal_distribution<double> noise(0.0, 0.05);
    std::ofstream out(bracket, std::ios::trunc);
    out << raylab::runs_csv_header() << "\n";
    for (int s = 0; s < 6; ++s)
      for (int i = 0; i < 8; ++i) {
        raylab::RunRecord r = *row;
        r.case_number = s * 8 + i;
        r.scene = "made-up-" + std::to_string(s);
        r.rays = "diffuse:" + std::to_string(1000 + i);
        if (s + i > 0) {  // the first row is the case itself
          r.primitives = static_cast<std::int64_t>(static_cast<double>(r.primitives) * jitter(rng));
          r.e_inner *= jitter(rng);
          r.e_leaves *= jitter(rng);
          r.e_tests *= jitter(rng);
          r.e_test_groups = r.e_tests / 4;
        }
        r.ns_per_ray_min = (10 + 2 * r.e_inner + 1.5 * r.e_tests) * std::exp(noise(rng));
        out << raylab::to_csv_row(r) << "\n";
        if (s < 2) {  // the cases of two scenes measured again, 25% slower: a replicate error of 0.25/1.125
          r.case_number += 1000;
          r.ns_per_ray_min *= 1.25;
          out << raylab::to_csv_row(r) << "\n";
        }
      }
  }
  const ToolRun bracket_fit = run_tool("fit --runs " + bracket.string() + " --out " + bracket_model.string());
  ASSERT_EQ(bracket_fit.status, 0) << bracket_fit.err;
  // A model error this far below the machine's (made-up) repeatability gets the verdict.
  EXPECT_NE(bracket_fit.out.find("replicate error 22.2% over 16 replicated cases; counters held-out MAPE"), std::string::npos)
      << bracket_fit.out;
  EXPECT_NE(bracket_fit.out.find("within 1.5x the replicate error: as good as this machine can tell"), std::string::npos)
      << bracket_fit.out;
  const ToolRun inside = run_tool("predict --model " + bracket_model.string() +
                                  " --scene sphere:n=400 --accel kdtree --rays diffuse:4096 --json");
  ASSERT_EQ(inside.status, 0) << inside.err;
  EXPECT_TRUE(inside.err.empty()) << inside.err;
  const auto ij = nlohmann::json::parse(inside.out);
  EXPECT_FALSE(ij.at("extrapolated").get<bool>());
  const auto interval = ij.at("interval90_ns_per_ray");
  ASSERT_TRUE(interval.is_array()) << inside.out;
  EXPECT_LT(interval[0].get<double>(), ij.at("predicted_ns_per_ray").get<double>());
  EXPECT_GT(interval[1].get<double>(), ij.at("predicted_ns_per_ray").get<double>());

  // Far outside the data (hundreds of times the primitives) it predicts, warns once naming the
  // feature and the factor, and widens the interval; --strict refuses; --allow-extrapolation is
  // still accepted.
  const std::string big = "predict --model " + bracket_model.string() + " --scene sphere:n=100000 --accel kdtree --rays diffuse:4096";
  const ToolRun far = run_tool(big + " --json");
  ASSERT_EQ(far.status, 0) << far.err;
  EXPECT_EQ(far.err.rfind("raylab: warning: kdtree is outside the model's data: primitives ", 0), 0u) << far.err;
  EXPECT_NE(far.err.find("x above the fitted"), std::string::npos) << far.err;
  EXPECT_NE(far.err.find("; the interval is widened"), std::string::npos) << far.err;
  EXPECT_EQ(std::count(far.err.begin(), far.err.end(), '\n'), 1) << far.err;
  const auto fj = nlohmann::json::parse(far.out);
  EXPECT_TRUE(fj.at("extrapolated").get<bool>());
  EXPECT_GT(fj.at("extrapolation_factor").get<double>(), kStrictFactorForTests);
  const auto wide = fj.at("interval90_ns_per_ray");
  ASSERT_TRUE(wide.is_array()) << far.out;
  EXPECT_GT(std::log(wide[1].get<double>() / wide[0].get<double>()),
            2 * std::log(interval[1].get<double>() / interval[0].get<double>()));
  expect_one_error_line(run_tool(big + " --strict"), big + " --strict");
  EXPECT_EQ(run_tool(big + " --allow-extrapolation").status, 0);

  // Every case measured twice (the copy 2% slower): the fit reports a replicate error of 2/101.
  const fs::path replicated = scratch_dir() / "replicated_runs.csv", model2 = scratch_dir() / "replicated_model.json";
  {
    std::ofstream out(replicated, std::ios::trunc);
    out << raylab::runs_csv_header() << "\n";
    for (raylab::RunRecord r : rows) {
      out << raylab::to_csv_row(r) << "\n";
      r.ns_per_ray_min *= 1.02;
      out << raylab::to_csv_row(r) << "\n";
    }
  }
  const ToolRun refit = run_tool("fit --runs " + replicated.string() + " --out " + model2.string() + " --json");
  ASSERT_EQ(refit.status, 0) << refit.err;
  const auto rj = nlohmann::json::parse(refit.out);
  EXPECT_NEAR(rj.at("families").at("kdtree").at("replicate_error").get<double>(), 0.02 / 1.01, 1e-9) << refit.out;
  EXPECT_EQ(rj.at("families").at("kdtree").at("replicate_groups").get<int>(), 4);  // 2 scenes x 2 ray sets
  EXPECT_TRUE(rj.at("families").at("kdtree").at("tree").at("held_out_coverage90").is_number()) << refit.out;
  const ToolRun refit_text = run_tool("fit --runs " + replicated.string() + " --out " + model2.string());
  ASSERT_EQ(refit_text.status, 0) << refit_text.err;
  EXPECT_NE(refit_text.out.find("replicate error 2.0% over 4 replicated cases"), std::string::npos) << refit_text.out;
}

TEST(CostCli, MergeNamesTheShardsLackingCasesAndWritesNothing) {
  const std::string plan = write_file("plan_merge.json", kSmallPlan);
  const raylab::SweepPlan p = raylab::load_plan(plan);
  // Shard K of 4 as raylab sweep writes it (timings aside).
  auto shard_file = [&](std::int64_t k, bool with_rows) {
    std::string text = raylab::runs_csv_header() + "\n";
    for (std::int64_t c = k; c < p.case_count() && with_rows; c += 4) {
      raylab::RunRecord r;
      const raylab::SweepCase key = p.case_at(c);
      r.case_number = c;
      r.scene = key.scene;
      r.accel = key.accel;
      r.rays = key.rays;
      text += raylab::to_csv_row(r) + "\n";
    }
    return write_file("merge_shard_" + std::to_string(k) + ".csv", text);
  };
  std::vector<std::string> files;
  for (std::int64_t k = 0; k < 4; ++k) files.push_back(shard_file(k, k != 2));  // shard 2 wrote its header only
  const fs::path out = scratch_dir() / "merged.csv";
  fs::remove(out);
  const std::string args = "merge --plan " + plan + " --shards 4 --out " + out.string() + " " + files[0] + " " + files[1] +
                           " " + files[2] + " " + files[3];
  const ToolRun r = run_tool(args);
  expect_one_error_line(r, args);
  EXPECT_EQ(r.out, "incomplete_shards=2\n");
  EXPECT_NE(r.err.find("5 of 20 cases missing (2, 6, 10, 14, 18), in shard 2 of 4"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out.string() + ".sweep.json"));

  // Bad input: one line, exit 2, nothing written.
  for (const std::string& bad : {"merge --plan " + plan + " --out " + out.string(),  // no shard files
                                 "merge --plan /no/such/plan.json --out " + out.string() + " " + files[0],
                                 "merge --plan " + plan + " --shards -2 --out " + out.string() + " " + files[0],
                                 "merge --plan " + plan + " --out " + out.string() + " " + plan}) {  // not a runs file
    expect_one_error_line(run_tool(bad), bad);
    EXPECT_FALSE(fs::exists(out)) << bad;
  }

  // The merge of every shard, and the plan check the lab's sweep validates plans with.
  shard_file(2, true);
  const ToolRun ok = run_tool(args);
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_EQ(raylab::read_runs_csv(out.string()).size(), 20u);
  const ToolRun check = run_tool("sweep --plan " + plan + " --check");
  ASSERT_EQ(check.status, 0) << check.err;
  EXPECT_NE(check.out.find(": 20 cases = 2 scenes x 5 accels x 2 rays"), std::string::npos) << check.out;
}

TEST(CostCli, TraceOfAutoPrintsItsChoice) {
  const ToolRun r = run_tool("trace --scene sphere:n=500 --accel auto --rays primary:1024 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("auto_choice")) << r.out;
  const auto& c = j["auto_choice"];
  EXPECT_FALSE(c.at("chosen").get<std::string>().empty());
  EXPECT_NE(c.at("model").get<std::string>().find("default_model.json"), std::string::npos);
  EXPECT_GE(c.at("candidates").size(), 8u);
}

}  // namespace
