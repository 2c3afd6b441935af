#include "scene/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "geometry/input_error.h"

namespace raylab {

namespace {

constexpr std::size_t kSinkBufferBytes = std::size_t{1} << 20;
constexpr std::uint64_t kMaxErrorMessageBytes = std::uint64_t{1} << 16;
constexpr std::uint8_t kResultTag = 0, kErrorTag = 1;

/// Writes all `bytes`; false when the reader has gone (EPIPE) or another error.
bool write_all(int fd, const char* data, std::size_t bytes) {
  while (bytes > 0) {
    const ssize_t n = ::write(fd, data, bytes);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    bytes -= static_cast<std::size_t>(n);
  }
  return true;
}

/// Waits for `pid`, retrying on EINTR; the wait status.
int reap(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 0;
  return status;
}

/// In the child: the fatal signals take their default action (a sanitizer's or a fuzzer's handler
/// would report the library's crash as raylab's), without a core file.
void die_by_default_on_fatal_signals() {
  for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS, SIGPIPE}) std::signal(sig, SIG_DFL);
  const rlimit no_core{0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);
}

}  // namespace

void PipeSink::write(const void* data, std::size_t bytes) {
  if (!begun_) buffer_.push_back(static_cast<char>(kResultTag));
  begun_ = true;
  const char* p = static_cast<const char*>(data);
  if (buffer_.size() + bytes <= kSinkBufferBytes) {
    buffer_.insert(buffer_.end(), p, p + bytes);
    return;
  }
  flush();
  if (!broken_ && !write_all(fd_, p, bytes)) broken_ = true;
}

void PipeSink::write_error(const std::string& message) {
  buffer_.clear();
  buffer_.push_back(static_cast<char>(kErrorTag));
  const std::uint64_t size = std::min<std::uint64_t>(message.size(), kMaxErrorMessageBytes);
  const char* s = reinterpret_cast<const char*>(&size);
  buffer_.insert(buffer_.end(), s, s + sizeof(size));
  buffer_.insert(buffer_.end(), message.data(), message.data() + size);
}

bool PipeSink::flush() {
  if (!broken_ && !buffer_.empty() && !write_all(fd_, buffer_.data(), buffer_.size())) broken_ = true;
  buffer_.clear();
  return !broken_;
}

void PipeSource::read(void* data, std::size_t bytes) {
  char* out = static_cast<char*>(data);
  const std::size_t buffered = std::min(bytes, buffer_.size() - begin_);
  if (buffered > 0) std::memcpy(out, buffer_.data() + begin_, buffered);
  begin_ += buffered;
  out += buffered;
  bytes -= buffered;
  while (bytes > 0) {
    wait_readable();
    const ssize_t n = ::read(fd_, out, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw OutputEnded{};
    out += n;
    bytes -= static_cast<std::size_t>(n);
  }
}

std::string PipeSource::get_string(std::uint64_t max_count) {
  std::string s(checked_count(get<std::uint64_t>(), max_count), '\0');
  read(s.data(), s.size());
  return s;
}

bool PipeSource::at_end() {
  if (begin_ < buffer_.size()) return false;
  char c;
  for (;;) {
    wait_readable();
    const ssize_t n = ::read(fd_, &c, 1);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return true;
    buffer_.assign(1, c);
    begin_ = 0;
    return false;
  }
}

void PipeSource::wait_readable() const {
  if (deadline_ == std::chrono::steady_clock::time_point::max()) return;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - std::chrono::steady_clock::now());
    if (left.count() <= 0) throw TimedOut{};
    pollfd p{fd_, POLLIN, 0};
    const int n = ::poll(&p, 1, static_cast<int>(std::min<std::int64_t>(left.count(), 60'000)));
    if (n > 0) return;  // readable, or the child closed its end (read sees the end)
    if (n < 0 && errno != EINTR) return;  // read reports the error
  }
}

std::size_t PipeSource::checked_count(std::uint64_t count, std::uint64_t max_count) {
  if (count > max_count)
    throw std::length_error("wrote a count of " + std::to_string(count) + ", more than " +
                            std::to_string(max_count));
  return static_cast<std::size_t>(count);
}

void run_in_child_process(const std::string& what, const std::function<void(PipeSink&)>& compute_and_write,
                          const std::function<void(PipeSource&)>& read, std::chrono::milliseconds time_limit) {
  const auto deadline = time_limit.count() > 0 ? std::chrono::steady_clock::now() + time_limit
                                               : std::chrono::steady_clock::time_point::max();
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw InputError(what + ": cannot create a pipe: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw InputError(what + ": cannot start a child process: " + std::strerror(e));
  }
  if (pid == 0) {
    ::close(fds[0]);
    die_by_default_on_fatal_signals();
    PipeSink sink(fds[1]);
    std::optional<std::string> error;
    try {
      compute_and_write(sink);
    } catch (const InputError& e) {
      error = e.what();
    } catch (const std::exception& e) {
      error = what + " failed: " + e.what();
    } catch (...) {
      error = what + " failed with an unknown exception";
    }
    int status = 0;
    if (error) {
      if (sink.begun()) status = 3;
      else sink.write_error(*error);
    }
    if (!sink.flush() && status == 0) status = 4;
    ::_exit(status);
  }
  ::close(fds[1]);
  // The parent gives up on the child: its end of the pipe closed, the child killed and reaped.
  auto stop_child = [&] {
    ::close(fds[0]);
    ::kill(pid, SIGKILL);
    reap(pid);
  };
  PipeSource source(fds[0], deadline);
  std::string child_error;
  bool ended = false;
  try {
    const auto tag = source.get<std::uint8_t>();
    if (tag == kErrorTag) {
      child_error = source.get_string(kMaxErrorMessageBytes);
    } else {
      read(source);
      if (!source.at_end()) throw std::length_error("wrote more than its result");
    }
  } catch (const PipeSource::OutputEnded&) {
    ended = true;
  } catch (const std::length_error& e) {
    stop_child();
    throw InputError(what + " " + e.what());
  } catch (const PipeSource::TimedOut&) {
    stop_child();
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.3g", static_cast<double>(time_limit.count()) * 1e-3);
    throw InputError(what + " did not finish within " + seconds + " s; raylab stopped it");
  } catch (...) {
    stop_child();
    throw;
  }
  ::close(fds[0]);
  const int status = reap(pid);
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = strsignal(sig);
    throw InputError(what + " crashed (signal " + std::to_string(sig) + ", " + (name ? name : "unknown") + ")");
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
    throw InputError(what + " exited with status " + std::to_string(WEXITSTATUS(status)) +
                     (ended ? " before its result was complete" : ""));
  if (ended) throw InputError(what + " ended before its result was complete");
  if (!child_error.empty()) throw InputError(child_error);
}

}  // namespace raylab
