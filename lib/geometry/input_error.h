#pragma once
/// The one exception type for bad user input (files, scene specs, ray specs, accelerator
/// parameters, non-finite values, empty scenes). Its message is one line a user can act on: it
/// names the file or spec, the line or element, and the fault. The `raylab` tool prints it as
/// `raylab: error: <message>` and exits with status 2.
#include <stdexcept>
#include <string>

namespace raylab {

/// `s` with its control characters (a newline or NUL copied from a bad spec or file) written as
/// \xNN, so that it prints as one line (found by the scene-spec fuzzer).
inline std::string one_line(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    } else {
      out += c;
    }
  }
  return out;
}

class InputError : public std::runtime_error {
 public:
  /// The message is made one line by one_line().
  explicit InputError(const std::string& message) : std::runtime_error(one_line(message)) {}
  explicit InputError(const char* message) : InputError(std::string(message)) {}
};

}  // namespace raylab
