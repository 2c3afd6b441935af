#include "cost/provenance.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
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

std::string first_line_of(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

CacheSizes sysconf_cache_sizes() {
  CacheSizes c;
  c.l1d = cache_bytes(_SC_LEVEL1_DCACHE_SIZE);
  c.l2 = cache_bytes(_SC_LEVEL2_CACHE_SIZE);
  c.l3 = cache_bytes(_SC_LEVEL3_CACHE_SIZE);
  if (c.l1d > 0 || c.l2 > 0 || c.l3 > 0) c.source = "sysconf";
  return c;
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

std::int64_t parse_cache_size(const std::string& text) {
  std::size_t i = 0, end = text.size();
  while (i < end && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  while (end > i && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  if (i == end || !std::isdigit(static_cast<unsigned char>(text[i]))) return -1;
  std::int64_t value = 0;
  for (; i < end && std::isdigit(static_cast<unsigned char>(text[i])); ++i) {
    if (value > (std::int64_t{1} << 40)) return -1;
    value = value * 10 + (text[i] - '0');
  }
  if (i == end) return value;
  if (i + 1 != end) return -1;
  switch (std::toupper(static_cast<unsigned char>(text[i]))) {
    case 'K': return value << 10;
    case 'M': return value << 20;
    case 'G': return value << 30;
    default: return -1;
  }
}

CacheSizes read_sysfs_cache_sizes(const std::string& cache_dir) {
  namespace fs = std::filesystem;
  CacheSizes c;
  std::error_code ec;
  if (!fs::is_directory(cache_dir, ec)) return c;
  for (const auto& entry : fs::directory_iterator(cache_dir, ec)) {
    if (entry.path().filename().string().rfind("index", 0) != 0) continue;
    const std::string type = first_line_of(entry.path() / "type");
    if (type != "Data" && type != "Unified") continue;
    const std::int64_t level = parse_cache_size(first_line_of(entry.path() / "level"));
    const std::int64_t size = parse_cache_size(first_line_of(entry.path() / "size"));
    if (size <= 0) continue;
    if (level == 1) c.l1d = size;
    else if (level == 2) c.l2 = size;
    else if (level == 3) c.l3 = size;
  }
  if (c.l1d > 0 || c.l2 > 0 || c.l3 > 0) c.source = "sysfs";
  return c;
}

CacheSizes reconcile_cache_sizes(const CacheSizes& sysfs, const CacheSizes& sysconf_sizes) {
  if (sysfs.source != "sysfs") return sysconf_sizes;
  CacheSizes c = sysfs;
  std::string differs;
  const std::pair<const char*, std::int64_t> ours[] = {{"L1d", sysfs.l1d}, {"L2", sysfs.l2}, {"L3", sysfs.l3}};
  const std::int64_t theirs[] = {sysconf_sizes.l1d, sysconf_sizes.l2, sysconf_sizes.l3};
  for (int k = 0; k < 3; ++k)
    if (theirs[k] > 0 && theirs[k] != ours[k].second)
      differs += std::string(" ") + ours[k].first + " " + std::to_string(theirs[k]);
  if (!differs.empty()) c.source = "sysfs; sysconf differs:" + differs;
  return c;
}

const Provenance& provenance_of_this_process() {
  static const Provenance p = [] {
    Provenance v;
    v.git_revision = RAYLAB_GIT_REVISION;
    char host[256] = {};
    v.host = gethostname(host, sizeof host - 1) == 0 ? host : "unknown";
    v.cpu_model = cpu_model_name();
    v.isa = build_isa();
    const CacheSizes caches = reconcile_cache_sizes(read_sysfs_cache_sizes(), sysconf_cache_sizes());
    v.l1d_bytes = caches.l1d;
    v.l2_bytes = caches.l2;
    v.llc_bytes = caches.last_level();
    v.cache_source = caches.source;
    return v;
  }();
  return p;
}

std::string raylab_data_dir() {
  if (const char* env = std::getenv("RAYLAB_DATA_DIR"); env && *env) return env;
  return RAYLAB_DATA_DIR;
}

}  // namespace raylab
