#include "cost/run_record.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <variant>

#include "cost/csv.h"
#include "geometry/input_error.h"
#include "geometry/spec_string.h"

namespace raylab {
namespace {

using Member = std::variant<std::string RunRecord::*, std::int64_t RunRecord::*, double RunRecord::*>;

struct Column {
  const char* name;
  Member member;
  bool optional = false;  ///< added after the first data sets: a file without it reads the default
};

/// The one table of columns: header, writer and reader all loop over it.
const std::vector<Column>& columns() {
  static const std::vector<Column> table = {
      {"case", &RunRecord::case_number},
      {"scene", &RunRecord::scene},
      {"accel", &RunRecord::accel},
      {"rays", &RunRecord::rays},
      {"family", &RunRecord::family},
      {"scene_family", &RunRecord::scene_family},
      {"ray_kind", &RunRecord::ray_kind},
      {"query", &RunRecord::query},
      {"primitives", &RunRecord::primitives},
      {"ray_count", &RunRecord::ray_count},
      {"threads", &RunRecord::threads},
      {"git_revision", &RunRecord::git_revision},
      {"host", &RunRecord::host},
      {"cpu_model", &RunRecord::cpu_model},
      {"isa", &RunRecord::isa},
      {"l2_bytes", &RunRecord::l2_bytes},
      {"llc_bytes", &RunRecord::llc_bytes},
      {"passes", &RunRecord::passes},
      {"clock", &RunRecord::clock},
      {"ns_per_ray_min", &RunRecord::ns_per_ray_min},
      {"ns_per_ray_median", &RunRecord::ns_per_ray_median},
      {"embree_ns_per_ray_min", &RunRecord::embree_ns_per_ray_min},
      {"build_s", &RunRecord::build_s},
      {"nodes_per_ray", &RunRecord::nodes_per_ray},
      {"leaves_per_ray", &RunRecord::leaves_per_ray},
      {"tests_per_ray", &RunRecord::tests_per_ray},
      {"hits_per_ray", &RunRecord::hits_per_ray},
      {"mailbox_skips_per_ray", &RunRecord::mailbox_skips_per_ray},
      {"hit_rate", &RunRecord::hit_rate},
      {"e_inner", &RunRecord::e_inner},
      {"e_leaves", &RunRecord::e_leaves},
      {"e_tests", &RunRecord::e_tests},
      {"e_test_groups", &RunRecord::e_test_groups},
      {"sah_1_1", &RunRecord::sah_1_1},
      {"epo", &RunRecord::epo},
      {"inner_nodes", &RunRecord::inner_nodes},
      {"leaves", &RunRecord::leaves},
      {"references", &RunRecord::references},
      {"depth", &RunRecord::depth},
      {"bytes", &RunRecord::bytes},
      {"replicate", &RunRecord::replicate, true},
      {"l1d_bytes", &RunRecord::l1d_bytes, true},
      {"cache_source", &RunRecord::cache_source, true},
      {"lines_per_ray_est", &RunRecord::lines_per_ray_est, true},
      {"working_set_bytes_est", &RunRecord::working_set_bytes_est, true},
      {"bytes_over_l2", &RunRecord::bytes_over_l2, true},
      {"bytes_over_llc", &RunRecord::bytes_over_llc, true},
      {"build_passes", &RunRecord::build_passes, true},
      {"ns_per_ray_max", &RunRecord::ns_per_ray_max, true},
      {"embree_ns_per_ray_max", &RunRecord::embree_ns_per_ray_max, true},
      {"build_s_max", &RunRecord::build_s_max, true},
      {"embree_bytes", &RunRecord::embree_bytes, true},
  };
  return table;
}

/// Shortest decimal that reads back to the same double.
std::string format_double(double v) {
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace

const std::vector<std::string>& run_record_columns() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const Column& c : columns()) n.push_back(c.name);
    return n;
  }();
  return names;
}

std::string runs_csv_header() {
  std::string line;
  for (const Column& c : columns()) {
    if (!line.empty()) line += ',';
    line += c.name;
  }
  return line;
}

std::string to_csv_row(const RunRecord& r) {
  std::string line;
  bool first = true;
  for (const Column& c : columns()) {
    if (!first) line += ',';
    first = false;
    std::visit(
        [&](auto member) {
          const auto& v = r.*member;
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<V, std::string>) line += csv_field(v);
          else if constexpr (std::is_same_v<V, double>) line += format_double(v);
          else line += std::to_string(v);
        },
        c.member);
  }
  return line;
}

std::vector<RunRecord> read_runs_csv(const std::string& path, bool allow_empty, std::size_t* truncated_tail) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the runs file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (text.empty()) throw InputError(path + ": empty file (expected the header line " + runs_csv_header().substr(0, 40) + "...)");

  std::vector<RunRecord> rows;
  std::vector<int> index_of;  // column table entry -> field index
  std::vector<std::string> fields;
  std::size_t pos = 0, line_no = 0;
  while (pos < text.size()) {
    const std::size_t end = text.find('\n', pos);
    ++line_no;
    const std::string where = path + ":" + std::to_string(line_no);
    if (end == std::string::npos) {
      if (truncated_tail && line_no > 1) {
        *truncated_tail = pos;
        break;
      }
      throw InputError(where + ": the last line has no line end (a sweep interrupted while writing? resume it)");
    }
    std::string_view row(text.data() + pos, end - pos);
    if (!row.empty() && row.back() == '\r') row.remove_suffix(1);
    pos = end + 1;
    if (!split_csv_row(row, fields)) throw InputError(where + ": malformed CSV (unbalanced quotes)");
    if (line_no == 1) {
      std::map<std::string, int> have;
      for (std::size_t i = 0; i < fields.size(); ++i) have[fields[i]] = static_cast<int>(i);
      for (const Column& c : columns()) {
        const auto it = have.find(c.name);
        if (it == have.end() && c.optional) {
          index_of.push_back(-1);
          continue;
        }
        if (it == have.end()) throw InputError(where + ": the header lacks the column '" + c.name + "' (not a runs file?)");
        index_of.push_back(it->second);
      }
      continue;
    }
    if (row.empty()) throw InputError(where + ": empty line");
    RunRecord r;
    for (std::size_t k = 0; k < columns().size(); ++k) {
      const Column& c = columns()[k];
      if (index_of[k] < 0) continue;  // an optional column the file lacks: the default
      const auto field_index = static_cast<std::size_t>(index_of[k]);
      if (field_index >= fields.size())
        throw InputError(where + ": " + std::to_string(fields.size()) + " fields, the column '" + c.name + "' is missing");
      const std::string& f = fields[field_index];
      std::visit(
          [&](auto member) {
            auto& v = r.*member;
            using V = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<V, std::string>) {
              v = f;
            } else if constexpr (std::is_same_v<V, double>) {
              if (!parse_double(f, v)) throw InputError(where + ": column '" + c.name + "': '" + f + "' is not a finite number");
            } else {
              if (!parse_int(f, v)) throw InputError(where + ": column '" + c.name + "': '" + f + "' is not an integer");
            }
          },
          c.member);
    }
    if (r.scene.empty() || r.accel.empty() || r.rays.empty()) throw InputError(where + ": empty scene, accel or rays");
    if (r.case_number < 0) throw InputError(where + ": negative case number");
    if (r.replicate < 0) throw InputError(where + ": negative replicate");
    rows.push_back(std::move(r));
  }
  if (truncated_tail && pos >= text.size()) *truncated_tail = text.size();
  if (rows.empty() && !allow_empty) throw InputError(path + ": the data set has no rows");
  return rows;
}

std::string scene_family_of(const std::string& scene_spec) {
  const SpecString spec = parse_spec(scene_spec);
  if (spec.name == "file" || spec.name.find_first_of("/.") != std::string::npos) return "file";
  static const char* derived[] = {"subdivided", "decimated", "transformed", "room", "instances"};
  for (const char* name : derived) {
    if (spec.name != name) continue;
    for (const auto& [key, value] : spec.params)
      if (key == "of") return scene_family_of(value);
  }
  return spec.name;
}

const char* ray_class_of(const std::string& kind) {
  if (kind == "diffuse") return "bounce";
  if (kind == "shadow" || kind == "ao") return "occlusion";
  if (kind == "lines") return "lines";
  return "camera";
}

bool ray_kind_incoherent(const std::string& kind) { return kind != "primary"; }

}  // namespace raylab
