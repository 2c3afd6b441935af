#include "cost/output_file.h"

#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <fstream>

#include "geometry/input_error.h"

namespace raylab {

void write_file_atomically(const std::string& path, const std::string& text) {
  // The process id keeps two writers of one target (two merges) off each other's temporary file.
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path + ": cannot write");
    out << text;
    if (!out.flush()) {
      out.close();
      std::filesystem::remove(tmp);
      throw InputError(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp);
    throw InputError(path + ": cannot write (" + ec.message() + ")");
  }
}

std::string utc_timestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buf;
}

}  // namespace raylab
