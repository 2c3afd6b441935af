#include "cost/merge.h"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "cost/output_file.h"

namespace raylab {
namespace {

/// "1, 5, 9" of at most `limit` numbers, then ", ... (N in all)".
std::string number_list(const std::vector<std::int64_t>& numbers, std::size_t limit = 8) {
  std::string s;
  for (std::size_t i = 0; i < numbers.size() && i < limit; ++i) s += (i ? ", " : "") + std::to_string(numbers[i]);
  if (numbers.size() > limit) s += ", ... (" + std::to_string(numbers.size()) + " in all)";
  return s;
}

std::string record_json(const SweepPlan& plan, const MergeResult& result, const std::string& note) {
  std::set<std::string> hosts, cpus, revisions;
  std::set<std::int64_t> threads;
  for (const RunRecord& r : result.rows) {
    hosts.insert(r.host);
    cpus.insert(r.cpu_model);
    revisions.insert(r.git_revision);
    threads.insert(r.threads);
  }
  nlohmann::ordered_json files = nlohmann::ordered_json::array();
  for (const ShardFileRows& f : result.files) files.push_back({{"file", f.path}, {"rows", f.rows}});
  const nlohmann::ordered_json j = {{"format", "raylab-sweep-merge"},
                                    {"version", 1},
                                    {"created", utc_timestamp()},
                                    {"plan", plan.source},
                                    {"plan_path", std::filesystem::absolute(plan_path(plan.source)).string()},
                                    {"cases", result.case_count},
                                    {"rows", result.rows.size()},
                                    {"shards", result.shard_count},
                                    {"how", note},
                                    {"shard_files", files},
                                    {"hosts", hosts},
                                    {"cpu_models", cpus},
                                    {"git_revisions", revisions},
                                    {"threads", threads}};
  // Strings from the shard files (hosts, CPU models) need not be UTF-8: replaced, not an exception.
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace

std::string merge_record_path(const std::string& out) { return out + ".sweep.json"; }

MergeResult collect_shards(const SweepPlan& plan, const std::vector<std::string>& shard_files, std::int64_t shard_count) {
  if (shard_files.empty()) throw InputError("merge: no shard files given");
  MergeResult result;
  result.case_count = plan.case_count();
  result.shard_count = shard_count > 0 ? shard_count : static_cast<std::int64_t>(shard_files.size());
  std::map<std::int64_t, std::vector<std::string>> where;  // case -> file:line
  for (const std::string& path : shard_files) {
    ShardFileRows f;
    f.path = path;
    f.exists = std::filesystem::exists(path);
    if (f.exists) {
      std::size_t complete = 0;
      std::vector<RunRecord> rows = read_runs_csv(path, true, &complete);
      f.torn_tail = complete < std::filesystem::file_size(path);
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const std::string at = path + ":" + std::to_string(i + 2);  // line 1 is the header
        check_row_in_plan(plan, rows[i], at);
        where[rows[i].case_number].push_back(at);
        result.rows.push_back(std::move(rows[i]));
      }
      f.rows = static_cast<std::int64_t>(rows.size());
    }
    result.files.push_back(f);
  }
  std::stable_sort(result.rows.begin(), result.rows.end(),
                   [](const RunRecord& a, const RunRecord& b) { return a.case_number < b.case_number; });
  std::set<std::int64_t> shards;
  for (std::int64_t c = 0; c < result.case_count; ++c) {
    const auto it = where.find(c);
    if (it == where.end()) {
      result.missing_cases.push_back(c);
      shards.insert(c % result.shard_count);
    } else if (it->second.size() > 1) {
      result.duplicates[c] = it->second;
    }
  }
  result.incomplete_shards.assign(shards.begin(), shards.end());
  return result;
}

std::string describe_incomplete(const MergeResult& r) {
  std::string s;
  if (!r.missing_cases.empty()) {
    s = "merge: " + std::to_string(r.missing_cases.size()) + " of " + std::to_string(r.case_count) +
        " cases missing (" + number_list(r.missing_cases) + "), in shard" + (r.incomplete_shards.size() > 1 ? "s " : " ") +
        number_list(r.incomplete_shards, 64) + " of " + std::to_string(r.shard_count) +
        ": rerun those shards with --resume, then merge again";
  }
  if (!r.duplicates.empty()) {
    s += s.empty() ? "merge: " : "; ";
    s += std::to_string(r.duplicates.size()) + " case" + (r.duplicates.size() > 1 ? "s" : "") + " more than once:";
    std::size_t shown = 0;
    for (const auto& [c, places] : r.duplicates) {
      if (shown++ == 4) {
        s += " ...";
        break;
      }
      s += " case " + std::to_string(c) + " in";
      for (const auto& p : places) s += " " + p;
      s += ";";
    }
    s += " shards of different plans or shard counts in one merge?";
  }
  return s + "; nothing written";
}

MergeResult merge_shards(const SweepPlan& plan, const MergeOptions& options) {
  namespace fs = std::filesystem;
  if (options.out.empty()) throw InputError("merge: --out is required");
  if (options.shard_count < 0) throw InputError("merge: --shards must be at least 1");
  if (fs::exists(options.out)) throw InputError(options.out + ": exists; merge into another --out, or remove it first");
  MergeResult result = collect_shards(plan, options.shard_files, options.shard_count);
  if (!result.complete()) throw IncompleteMerge(std::move(result));

  std::string csv = runs_csv_header() + "\n";
  for (const RunRecord& r : result.rows) csv += to_csv_row(r) + "\n";
  const std::string record = merge_record_path(options.out);
  write_file_atomically(record, record_json(plan, result, options.note));
  try {
    write_file_atomically(options.out, csv);
  } catch (...) {
    fs::remove(record);
    throw;
  }
  return result;
}

}  // namespace raylab
