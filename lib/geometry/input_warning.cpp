#include "geometry/input_warning.h"

#include <cstdio>
#include <mutex>
#include <set>

#include "geometry/input_error.h"

namespace raylab {

void warn_input(const std::string& message) {
  static std::mutex m;
  std::string line = "raylab: warning: ";
  line += one_line(message);
  line += '\n';
  std::lock_guard lock(m);
  std::fputs(line.c_str(), stderr);
}

void warn_input_once(const std::string& key, const std::string& message) {
  static std::mutex m;
  static std::set<std::string> warned;
  {
    std::lock_guard lock(m);
    if (!warned.insert(key).second) return;
  }
  warn_input(message);
}

}  // namespace raylab
