#pragma once
/// Where a measurement was taken: the identity columns every data set row records, so that a fit
/// can refuse (or model) rows from different machines or builds.
#include <cstdint>
#include <string>

namespace raylab {

struct Provenance {
  std::string git_revision;  ///< `git describe --always --dirty` of the build
  std::string host;          ///< the node's host name
  std::string cpu_model;     ///< /proc/cpuinfo's model name
  std::string isa;           ///< the widest vector ISA the build targets: AVX-512, AVX2, SSE4.2 or baseline
  std::int64_t l1d_bytes = 0;  ///< the level-1 data cache size (0 when unknown)
  std::int64_t l2_bytes = 0;   ///< the per-core level-2 cache size (0 when unknown)
  std::int64_t llc_bytes = 0;  ///< the last-level cache size (0 when unknown)
  std::string cache_source;    ///< CacheSizes::source of the three sizes
};

/// The data-cache sizes of one CPU, in bytes (0 when unknown), and where they were read.
///
/// `source` is "sysfs" (the kernel's cache/index*/ files, which describe the cache the CPU has),
/// "sysconf" (glibc's _SC_LEVEL*_CACHE_SIZE, from CPUID; on virtual machines it may report the
/// host's or a sum over cores: 320 MiB for a 32 MiB L3 was seen), or "none". When both are known
/// and differ, sysfs is used and `source` says so, with sysconf's figures, e.g.
/// "sysfs; sysconf differs: L2 1048576 L3 335544320".
struct CacheSizes {
  std::int64_t l1d = 0, l2 = 0, l3 = 0;
  std::string source = "none";
  std::int64_t last_level() const { return l3 > 0 ? l3 : l2 > 0 ? l2 : l1d; }
};

/// A sysfs cache size: a decimal count of bytes with an optional K, M or G suffix (binary
/// multiples: "48K" = 49152, "32M" = 33554432), surrounding white space allowed. -1 when malformed.
std::int64_t parse_cache_size(const std::string& text);

/// The data and unified caches that sysfs lists under `cache_dir` (cpu0's by default): each
/// index*/ holding `level`, `type` (Data, Unified; Instruction is skipped) and `size`. Zeros
/// where a level is missing or unreadable.
CacheSizes read_sysfs_cache_sizes(const std::string& cache_dir = "/sys/devices/system/cpu/cpu0/cache");

/// Sizes from sysfs, checked against sysconf's (`sysconf_sizes`), as CacheSizes::source describes.
CacheSizes reconcile_cache_sizes(const CacheSizes& sysfs, const CacheSizes& sysconf_sizes);

/// This process's provenance (read once).
const Provenance& provenance_of_this_process();

/// The directory of the shipped sweep plans and the default cost model (the source tree's data/,
/// or $RAYLAB_DATA_DIR when set).
std::string raylab_data_dir();

}  // namespace raylab
