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
  std::int64_t l2_bytes = 0;   ///< the per-core level-2 cache size (0 when unknown)
  std::int64_t llc_bytes = 0;  ///< the last-level cache size as the system reports it (0 when unknown)
};

/// This process's provenance (read once).
const Provenance& provenance_of_this_process();

/// The directory of the shipped sweep plans and the default cost model (the source tree's data/,
/// or $RAYLAB_DATA_DIR when set).
std::string raylab_data_dir();

}  // namespace raylab
