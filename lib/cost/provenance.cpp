#include "cost/provenance.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>

#include "raylab_git_revision.h"

namespace raylab {
namespace {

std::string cpu_model_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) break;
    std::string name = line.substr(colon + 1);
    name.erase(0, name.find_first_not_of(" \t"));
    return name;
  }
  return "unknown";
}

/// A cache size as sysconf reports it (virtual machines may report the host's), 0 when unknown.
std::int64_t cache_bytes(int name) {
  const long bytes = sysconf(name);
  return bytes > 0 ? bytes : 0;
}

const char* build_isa() {
#if defined(__AVX512F__)
  return "AVX-512";
#elif defined(__AVX2__)
  return "AVX2";
#elif defined(__SSE4_2__)
  return "SSE4.2";
#else
  return "baseline";
#endif
}

}  // namespace

const Provenance& provenance_of_this_process() {
  static const Provenance p = [] {
    Provenance v;
    v.git_revision = RAYLAB_GIT_REVISION;
    char host[256] = {};
    v.host = gethostname(host, sizeof host - 1) == 0 ? host : "unknown";
    v.cpu_model = cpu_model_name();
    v.isa = build_isa();
    v.l2_bytes = cache_bytes(_SC_LEVEL2_CACHE_SIZE);
    v.llc_bytes = std::max(v.l2_bytes, cache_bytes(_SC_LEVEL3_CACHE_SIZE));
    return v;
  }();
  return p;
}

std::string raylab_data_dir() {
  if (const char* env = std::getenv("RAYLAB_DATA_DIR"); env && *env) return env;
  return RAYLAB_DATA_DIR;
}

}  // namespace raylab
