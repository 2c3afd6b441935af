// run_in_child_process (lib/scene/child_process.h): a result crosses the pipe intact, and every way a
// child can fail (an exception, a signal, an abort, an early exit, a count past its cap) becomes one
// InputError in the parent, which goes on.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <numeric>

#include "geometry/input_error.h"
#include "scene/child_process.h"

namespace {

using raylab::InputError;
using raylab::PipeSink;
using raylab::PipeSource;

struct Payload {
  std::string name;
  std::vector<float> values;
};

Payload round_trip(std::size_t count) {
  return raylab::run_in_child_process<Payload>(
      "test child",
      [&] {
        Payload p{"values", std::vector<float>(count)};
        std::iota(p.values.begin(), p.values.end(), 0.5f);
        return p;
      },
      [](PipeSink& sink, const Payload& p) {
        sink.put_string(p.name);
        sink.put_vector(p.values);
      },
      [](PipeSource& source) {
        Payload p;
        p.name = source.get_string(64);
        p.values = source.get_vector<float>(std::uint64_t{1} << 26);
        return p;
      });
}

std::string error_of(const std::function<void(PipeSink&)>& child,
                     const std::function<void(PipeSource&)>& parent = [](PipeSource& s) { s.get_vector<float>(1 << 20); }) {
  try {
    raylab::run_in_child_process("test child", child, parent);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(ChildProcess, ResultCrossesThePipeIntact) {
  for (const std::size_t count : {std::size_t{0}, std::size_t{3}, std::size_t{3} << 20}) {  // 12 MiB: more than a pipe holds
    const Payload p = round_trip(count);
    EXPECT_EQ(p.name, "values");
    ASSERT_EQ(p.values.size(), count);
    for (std::size_t i = 0; i < count; i += 4099) EXPECT_EQ(p.values[i], 0.5f + static_cast<float>(i));
  }
}

TEST(ChildProcess, ExceptionsReachTheParentAsInputErrors) {
  EXPECT_EQ(error_of([](PipeSink&) { throw InputError("file.fbx: bad header"); }), "file.fbx: bad header");
  EXPECT_EQ(error_of([](PipeSink&) { throw std::runtime_error("boom"); }), "test child failed: boom");
  // Thrown once the result has begun: the message cannot follow, the exit status says it.
  EXPECT_EQ(error_of([](PipeSink& s) {
              s.put<std::uint64_t>(100);
              throw InputError("late");
            }),
            "test child exited with status 3 before its result was complete");
}

TEST(ChildProcess, CrashesAndEarlyExitsAreNamed) {
  EXPECT_NE(error_of([](PipeSink&) { std::raise(SIGSEGV); }).find("test child crashed (signal 11"), std::string::npos);
  EXPECT_NE(error_of([](PipeSink& s) {
              s.put<std::uint64_t>(8);
              s.flush();
              std::abort();
            }).find("test child crashed (signal 6"),
            std::string::npos);
  EXPECT_EQ(error_of([](PipeSink&) { ::_exit(7); }), "test child exited with status 7 before its result was complete");
  EXPECT_EQ(error_of([](PipeSink&) {}), "test child ended before its result was complete");
}

TEST(ChildProcess, AChildPastItsTimeLimitIsStopped) {
  const auto start = std::chrono::steady_clock::now();
  std::string e = "no error";
  try {
    raylab::run_in_child_process(
        "test child", [](PipeSink&) { ::sleep(30); }, [](PipeSource& s) { s.get<std::uint64_t>(); },
        std::chrono::milliseconds(300));
  } catch (const InputError& error) {
    e = error.what();
  }
  EXPECT_EQ(e, "test child did not finish within 0.3 s; raylab stopped it");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(ChildProcess, CountsAreCheckedBeforeAllocating) {
  const std::string e = error_of([](PipeSink& s) { s.put<std::uint64_t>(std::uint64_t{1} << 60); });
  EXPECT_NE(e.find("test child wrote a count of 1152921504606846976, more than 1048576"), std::string::npos) << e;
  // A parent that stops reading early does not wait for the whole result.
  EXPECT_EQ(error_of([](PipeSink& s) { s.put_vector(std::vector<float>(std::size_t{1} << 22)); },
                     [](PipeSource& s) { s.get<std::uint64_t>(); }),
            "test child wrote more than its result");
}
