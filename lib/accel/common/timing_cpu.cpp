#include "accel/common/timing_cpu.h"

#include <tbb/info.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <string>

#include "accel/common/tracer.h"
#include "geometry/input_error.h"

namespace raylab {

namespace {

constexpr const char* kVariable = "RAYLAB_TIMING_CPU";

std::string allowed_cpus(const cpu_set_t& mask) {
  std::string list;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &mask)) {
      if (!list.empty()) list += ',';
      list += std::to_string(c);
    }
  return list.empty() ? "none" : list;
}

}  // namespace

int timing_cpu() {
  const char* value = std::getenv(kVariable);
  if (!value || !*value) return -1;
  const std::string text(value);
  cpu_set_t mask;
  CPU_ZERO(&mask);
  if (sched_getaffinity(0, sizeof mask, &mask) != 0)
    throw InputError(std::string(kVariable) + "=" + text + ": cannot read this thread's CPU affinity");
  char* end = nullptr;
  errno = 0;
  const long cpu = std::strtol(value, &end, 10);
  // Digits only: no sign, no leading space (strtol would accept both).
  if (errno != 0 || !std::isdigit(static_cast<unsigned char>(value[0])) || *end != '\0' || cpu >= CPU_SETSIZE ||
      !CPU_ISSET(cpu, &mask))
    throw InputError(std::string(kVariable) + "=" + text + ": not a CPU this process may run on (allowed: " +
                     allowed_cpus(mask) + ")");
  return static_cast<int>(cpu);
}

TimingCpuScope::TimingCpuScope(bool pin) {
  const int cpu = pin ? timing_cpu() : -1;
  if (cpu < 0) return;
  // TBB reads its default concurrency from the affinity mask of the thread that first asks, once:
  // ask before the pin, or a process whose first TBB call is pinned would run every later
  // multi-thread section on one thread.
  static const int tbb_concurrency = tbb::info::default_concurrency();
  (void)tbb_concurrency;
  if (sched_getaffinity(0, sizeof saved_mask_, &saved_mask_) != 0) return;
  cpu_set_t pinned;
  CPU_ZERO(&pinned);
  CPU_SET(cpu, &pinned);
  if (sched_setaffinity(0, sizeof pinned, &pinned) == 0) cpu_ = cpu;
}

TimingCpuScope::~TimingCpuScope() {
  if (cpu_ >= 0) sched_setaffinity(0, sizeof saved_mask_, &saved_mask_);
}

TimingArena::TimingArena(int threads)
    : threads_(resolve_thread_count(threads)), pinned_(threads_ == 1), arena_(threads_) {}

}  // namespace raylab
