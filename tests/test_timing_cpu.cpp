// RAYLAB_TIMING_CPU (accel/common/timing_cpu.h): single-thread timings run on the named CPU, the
// thread's affinity comes back afterwards, multi-thread traces keep every CPU, and a value that is
// not a CPU of this process is one error naming the variable.
#include <gtest/gtest.h>
#include <sched.h>
#include <tbb/info.h>

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "geometry/input_error.h"

using namespace raylab;

namespace {

cpu_set_t this_thread_mask() {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  EXPECT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  return mask;
}

int last_allowed_cpu() {
  const cpu_set_t mask = this_thread_mask();
  int last = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &mask)) last = c;
  return last;
}

/// Sets RAYLAB_TIMING_CPU for one test and unsets it afterwards.
class TimingCpuVariable {
 public:
  explicit TimingCpuVariable(const std::string& value) { setenv("RAYLAB_TIMING_CPU", value.c_str(), 1); }
  ~TimingCpuVariable() { unsetenv("RAYLAB_TIMING_CPU"); }
};

/// A primitive that never hits and records the CPU and the thread of every query.
class CpuRecordingPrimitive final : public Primitive {
 public:
  Bounds3f bounds() const override { return {}; }
  bool intersect(Ray&, Hit&) const override { return record(); }
  bool intersect(Ray&, Hit&, RayCounters&) const override { return record(); }
  bool occluded(const Ray&) const override { return record(); }
  bool occluded(const Ray&, RayCounters&) const override { return record(); }

  std::set<int> cpus() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cpus_;
  }
  std::size_t threads() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return threads_.size();
  }

 private:
  bool record() const {
    const int cpu = sched_getcpu();
    // Long enough per ray that a parallel trace hands work to the other threads.
    volatile double spin = 0;
    for (int i = 0; i < 20000; ++i) spin = spin + 1.0;
    std::lock_guard<std::mutex> lock(mutex_);
    cpus_.insert(cpu);
    threads_.insert(std::this_thread::get_id());
    return false;
  }
  mutable std::mutex mutex_;
  mutable std::set<int> cpus_;
  mutable std::set<std::thread::id> threads_;
};

bool same_mask(const cpu_set_t& a, const cpu_set_t& b) { return CPU_EQUAL(&a, &b); }

}  // namespace

TEST(TimingCpu, UnsetPinsNothing) {
  unsetenv("RAYLAB_TIMING_CPU");
  EXPECT_EQ(timing_cpu(), -1);
  const cpu_set_t before = this_thread_mask();
  {
    const TimingCpuScope scope;
    EXPECT_EQ(scope.cpu(), -1);
    EXPECT_TRUE(same_mask(this_thread_mask(), before));
  }
  const TimingCpuVariable empty("");
  EXPECT_EQ(timing_cpu(), -1);
}

TEST(TimingCpu, ScopePinsToTheNamedCpuAndRestores) {
  const int cpu = last_allowed_cpu();
  ASSERT_GE(cpu, 0);
  const TimingCpuVariable variable(std::to_string(cpu));
  EXPECT_EQ(timing_cpu(), cpu);
  const cpu_set_t before = this_thread_mask();
  {
    const TimingCpuScope scope;
    EXPECT_EQ(scope.cpu(), cpu);
    EXPECT_EQ(sched_getcpu(), cpu);
    const cpu_set_t pinned = this_thread_mask();
    EXPECT_EQ(CPU_COUNT(&pinned), 1);
    {
      const TimingCpuScope nested;  // a timed trace inside a timed section
      EXPECT_EQ(sched_getcpu(), cpu);
    }
    EXPECT_EQ(sched_getcpu(), cpu);
    const TimingCpuScope off(false);
    EXPECT_EQ(off.cpu(), -1);
  }
  EXPECT_TRUE(same_mask(this_thread_mask(), before));
}

TEST(TimingCpu, SingleThreadTraceRunsOnTheTimingCpuAndParallelTracesKeepEveryCpu) {
  const int cpu = last_allowed_cpu();
  ASSERT_GE(cpu, 0);
  const cpu_set_t mask = this_thread_mask();
  const int allowed = CPU_COUNT(&mask);
  const TimingCpuVariable variable(std::to_string(cpu));
  const std::vector<Ray> rays(4096, Ray{{0, 0, 0}, {0, 0, 1}});
  {
    // The process's first TBB work is this pinned trace: TBB must still see every CPU afterwards.
    CpuRecordingPrimitive prim;
    trace_rays(prim, rays, TraceOptions{1, false, false});
    EXPECT_EQ(prim.cpus(), std::set<int>{cpu});
    EXPECT_EQ(prim.threads(), 1u);
  }
  EXPECT_EQ(tbb::info::default_concurrency(), allowed);
  if (allowed < 2) GTEST_SKIP() << "one CPU: no parallel trace to check";
  CpuRecordingPrimitive prim;
  trace_rays(prim, rays, TraceOptions{2, false, true});
  EXPECT_EQ(prim.threads(), 2u) << "a 2-thread trace after a pinned one ran on fewer threads";
}

TEST(TimingCpu, BadValueIsOneErrorNamingTheVariable) {
  for (const std::string& bad : std::vector<std::string>{"x", "-1", "1x", " 0", "99999999999999999999", std::to_string(CPU_SETSIZE),
                                std::to_string(CPU_SETSIZE - 1)}) {
    const TimingCpuVariable variable(bad);
    try {
      (void)timing_cpu();
      ADD_FAILURE() << "accepted RAYLAB_TIMING_CPU='" << bad << "'";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("RAYLAB_TIMING_CPU=" + bad + ": not a CPU this process may run on (allowed: "),
                std::string::npos)
          << message;
      EXPECT_EQ(message.find('\n'), std::string::npos);
    }
    EXPECT_THROW(TimingCpuScope{}, InputError);
  }
}
