#pragma once
/// Files the cost layer writes whole (merged data sets, model files, merge records): written to
/// a temporary file beside the target and renamed over it, so that neither a reader nor a failed
/// write ever leaves a partial file under the target's name.
#include <string>

namespace raylab {

/// Writes `text` to `path` atomically. Throws InputError naming `path` when it cannot be written;
/// the temporary file is removed then.
void write_file_atomically(const std::string& path, const std::string& text);

/// The current time as ISO 8601 UTC, e.g. 2026-12-01T20:00:00Z (the `created` of output files).
std::string utc_timestamp();

}  // namespace raylab
