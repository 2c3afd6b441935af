#pragma once
/// The CPU that single-thread timings run on.
///
/// On a virtual machine the vCPUs need not be equal: one may share its physical core with another
/// guest. Measured on this lab's 2-vCPU machines, the same binary's `bvh` took 284 ns per diffuse
/// ray on one vCPU and 236 ns on the other, for 8% of Embree's time against 20% of ours, so a
/// single-thread figure (and even a ratio to Embree) depends on where the scheduler put the thread.
/// `./lab report` measures each vCPU first and names the fastest in `RAYLAB_TIMING_CPU`; every
/// single-thread timing of the library and the experiments then runs on that CPU.
///
/// Contract: with `RAYLAB_TIMING_CPU` unset or empty nothing is pinned. Otherwise it must be a
/// CPU number this process may run on (in the calling thread's affinity mask), or
/// timing_cpu() throws InputError naming the variable, the value and the allowed CPUs.
#include <sched.h>
#include <tbb/task_arena.h>

#include <utility>

namespace raylab {

/// The CPU named by `RAYLAB_TIMING_CPU`, or -1 when it is unset or empty. Read on every call and
/// checked against the calling thread's affinity mask.
int timing_cpu();

/// For its lifetime, the calling thread runs on timing_cpu() alone (when one is named); the
/// thread's previous affinity is restored at the end. TBB's default concurrency is fixed before the
/// first pin, so a pinned single-thread section does not shrink later multi-thread ones.
class TimingCpuScope {
 public:
  /// `pin` false: a scope that does nothing (for callers that pin only their single-thread case).
  explicit TimingCpuScope(bool pin = true);
  ~TimingCpuScope();
  TimingCpuScope(const TimingCpuScope&) = delete;
  TimingCpuScope& operator=(const TimingCpuScope&) = delete;

  /// The CPU this scope pinned the thread to, or -1.
  int cpu() const { return cpu_; }

 private:
  int cpu_ = -1;
  cpu_set_t saved_mask_{};  ///< the thread's affinity before the pin
};

/// A TBB arena of `threads` threads (0: every hardware thread, resolve_thread_count) for timed
/// work. With one thread the calling thread, which then runs all of the arena's work, is pinned to
/// timing_cpu() for the arena's lifetime (TimingCpuScope); with more, nothing is pinned.
class TimingArena {
 public:
  explicit TimingArena(int threads);

  int threads() const { return threads_; }
  template <class F>
  decltype(auto) execute(F&& f) {
    return arena_.execute(std::forward<F>(f));
  }

 private:
  int threads_;
  TimingCpuScope pinned_;
  tbb::task_arena arena_;
};

}  // namespace raylab
