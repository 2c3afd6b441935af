#pragma once
/// The one exception type for bad user input (files, scene specs, ray specs, accelerator
/// parameters, non-finite values, empty scenes). Its message is one line a user can act on: it
/// names the file or spec, the line or element, and the fault. The `raylab` tool prints it as
/// `raylab: error: <message>` and exits with status 2.
#include <stdexcept>
#include <string>

namespace raylab {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace raylab
