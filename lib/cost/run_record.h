#pragma once
/// One measured case of the cost model's data set (`raylab sweep`): its identity, its timing, its
/// counters and the features of its structure, and its row in `runs.csv`. The sweep, the fit,
/// `predict` and the merge of sharded sweeps all read and write this one type.
///
/// runs.csv is RFC 4180 CSV (csv.h) with a header naming the columns of run_record_columns(), in
/// that order when the lab writes it; a reader takes them in any order and ignores extra columns.
/// Times are nanoseconds per ray of the clock `clock` names (timing.h: the tracing thread's CPU
/// time for single-threaded passes, else wall clock); counters and features are per ray.
///
/// Columns added after the first data sets (replicate, the cache sizes' source, the memory
/// features) are optional when reading: a file without them reads with their defaults, so older
/// runs CSVs stay readable.
#include <cstdint>
#include <string>
#include <vector>

namespace raylab {

struct RunRecord {
  // Identity: (scene, accel, rays) is the case's key; `case_number` its index in the plan.
  std::int64_t case_number = 0;
  std::string scene, accel, rays;
  std::string family;        ///< structure family (tree_features.h: structure_family)
  std::string scene_family;  ///< scene_family_of(scene)
  std::string ray_kind;      ///< the ray spec's generator name: primary, diffuse, shadow, lines, ...
  std::string query;         ///< intersect | occluded
  std::int64_t primitives = 0;
  std::int64_t ray_count = 0;
  std::int64_t threads = 1;
  std::string git_revision, host, cpu_model, isa;
  std::int64_t l2_bytes = 0;   ///< level-2 cache of the CPU that measured the row (provenance.h)
  std::int64_t llc_bytes = 0;  ///< its last-level cache

  // Timing: passes with counters compiled out, Embree's passes alternating with ours.
  std::int64_t passes = 0;
  std::string clock;  ///< thread_cpu | wall
  double ns_per_ray_min = 0, ns_per_ray_median = 0;
  double ns_per_ray_max = 0;  ///< the slowest pass ([min, max]: the passes' range); 0 in data sets before the column
  double embree_ns_per_ray_min = 0;
  double build_s = 0;            ///< the fastest of build_passes builds (sweep.h: kSweepBuildPasses)
  std::int64_t build_passes = 1;  ///< 1 in data sets written before the column
  double embree_ns_per_ray_max = 0;  ///< Embree's slowest pass; 0 in data sets before the column
  double build_s_max = 0;            ///< the slowest build ([build_s, build_s_max]); 0 in data sets before the column
  /// Bytes of the Embree scene the row was timed against (its BVH and geometry buffers, counted by
  /// Embree's memory monitor; embree_accel.cpp); 0 in data sets before the column. Measured, not
  /// counted: Embree's allocator may round differently from run to run.
  std::int64_t embree_bytes = 0;

  // Counters, per ray, from a separate counted pass.
  double nodes_per_ray = 0, leaves_per_ray = 0, tests_per_ray = 0, hits_per_ray = 0, mailbox_skips_per_ray = 0;
  double hit_rate = 0;

  // Features of the structure alone (tree_features.h).
  double e_inner = 0, e_leaves = 0, e_tests = 0, e_test_groups = 0, sah_1_1 = 0, epo = 0;
  std::int64_t inner_nodes = 0, leaves = 0, references = 0, depth = 0, bytes = 0;

  // Replicates (sweep.h): 0 for a case's first measurement, k for its k-th repeat, which has its
  // own case number and the same (scene, accel, rays).
  std::int64_t replicate = 0;

  // The cache sizes of provenance.h beside l2_bytes and llc_bytes.
  std::int64_t l1d_bytes = 0;
  std::string cache_source;  ///< provenance.h: CacheSizes::source

  // Memory features (tree_features.h: fill_memory_features). Estimates, not measured addresses.
  double lines_per_ray_est = 0;      ///< distinct 64-byte lines of structure data one ray touches
  double working_set_bytes_est = 0;  ///< structure bytes a batch of kWorkingSetBatch random lines touches
  double bytes_over_l2 = 0;          ///< bytes / l2_bytes (0 when the size is unknown)
  double bytes_over_llc = 0;         ///< bytes / llc_bytes (0 when the size is unknown)

  bool any_hit() const { return query == "occluded"; }
};

/// The column names, in the order the lab writes them.
const std::vector<std::string>& run_record_columns();

/// The header line and one row (no line end).
std::string runs_csv_header();
std::string to_csv_row(const RunRecord& record);

/// Reads a runs CSV. Throws InputError naming the file and line for a missing file, a missing
/// column, a malformed or non-finite field; with `allow_empty` false also for a data set with no
/// rows. A last line without its line end (a sweep killed while writing) is an error unless
/// `truncated_tail` is given, which then receives the byte offset where the complete rows end.
std::vector<RunRecord> read_runs_csv(const std::string& path, bool allow_empty = false,
                                     std::size_t* truncated_tail = nullptr);

/// The family of a scene spec for model selection: the spec's kind name, with derived scenes
/// (subdivided, decimated, transformed, room, instances) taking their base's family.
std::string scene_family_of(const std::string& scene_spec);

/// The class of a ray kind for the tree model (cost_model.h): camera (primary, and the rays aimed
/// from outside: edges, vertices, file), bounce (diffuse), occlusion (shadow, ao) or lines.
const char* ray_class_of(const std::string& ray_kind);
/// Ray kinds without coherence between neighbouring rays: everything but primary.
bool ray_kind_incoherent(const std::string& ray_kind);

}  // namespace raylab
