#pragma once
/// Runs a computation in a child process made by fork(2), so that a crash, an abort or a failed
/// assertion in a library it calls ends the child, not raylab. Assimp 5.2.5 validates less than
/// raylab needs: malformed FBX and COLLADA files make it dereference null or wrapped pointers and
/// abort on its own ai_assert (found by tests/fuzz/fuzz_scene_import). raylab's checks before
/// Assimp (scene_import.h) catch the faults they know; this contains the ones nobody knows yet.
///
/// The child computes its result, then streams it through a pipe (PipeSink); the parent reads it
/// while it is written (PipeSource), so a result is never held twice in one process. The child
/// resets the fatal signals to their default action, so it dies by the signal, which the parent
/// names; it leaves by _exit(2), running no atexit handler of the parent's.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

namespace raylab {

/// The writing end of the pipe, in the child: buffered, raw host-order bytes. The first write
/// marks the result as begun (run_in_child_process).
class PipeSink {
 public:
  explicit PipeSink(int fd) : fd_(fd) {}
  void write(const void* data, std::size_t bytes);
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    write(&value, sizeof(T));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    write(s.data(), s.size());
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(v.size());
    write(v.data(), v.size() * sizeof(T));
  }
  /// Writes the buffer out; false when the parent no longer reads.
  bool flush();
  /// True once anything was written.
  bool begun() const { return begun_; }
  /// Replaces a result not yet begun by an error message (run_in_child_process).
  void write_error(const std::string& message);

 private:
  int fd_;
  std::vector<char> buffer_;
  bool begun_ = false, broken_ = false;
};

/// The reading end, in the parent. Every read throws OutputEnded when the child's output ends
/// before the value does (the child died: run_in_child_process says how).
class PipeSource {
 public:
  struct OutputEnded {};
  struct TimedOut {};  ///< the deadline passed while waiting for the child's output
  explicit PipeSource(int fd, std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max())
      : fd_(fd), deadline_(deadline) {}
  void read(void* data, std::size_t bytes);
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    read(&value, sizeof(T));
    return value;
  }
  /// A string or vector of at most `max_count` elements, checked before anything is allocated;
  /// a larger count throws std::length_error (the child writes only counts it has checked).
  std::string get_string(std::uint64_t max_count);
  template <class T>
  std::vector<T> get_vector(std::uint64_t max_count) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::vector<T> v(checked_count(get<std::uint64_t>(), max_count));
    read(v.data(), v.size() * sizeof(T));
    return v;
  }
  /// True when the child wrote nothing more.
  bool at_end();

 private:
  static std::size_t checked_count(std::uint64_t count, std::uint64_t max_count);
  /// Waits until the pipe can be read; throws TimedOut past the deadline.
  void wait_readable() const;
  int fd_;
  std::chrono::steady_clock::time_point deadline_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;
};

/// Runs `compute_and_write` in a child process and `read` in the parent on what it writes.
/// An exception that `compute_and_write` throws before its first write reaches the parent as an
/// InputError with the same message (one other than InputError is prefixed by `what`); one thrown
/// later ends the child with status 3. Throws InputError("`what`: ...") when the child dies by a
/// signal (named), exits before its result is complete or with a non-zero status, does not finish
/// within `time_limit` (zero: no limit; the child is then killed), or when pipe(2) or fork(2) fail.
void run_in_child_process(const std::string& what, const std::function<void(PipeSink&)>& compute_and_write,
                          const std::function<void(PipeSource&)>& read,
                          std::chrono::milliseconds time_limit = std::chrono::milliseconds::zero());

/// The typed form: `compute` runs in the child, `write` streams its result, `read` rebuilds it.
template <class Result, class Compute, class Write, class Read>
Result run_in_child_process(const std::string& what, Compute compute, Write write, Read read,
                            std::chrono::milliseconds time_limit = std::chrono::milliseconds::zero()) {
  Result result{};
  run_in_child_process(
      what, [&](PipeSink& sink) { write(sink, compute()); }, [&](PipeSource& source) { result = read(source); },
      time_limit);
  return result;
}

}  // namespace raylab
