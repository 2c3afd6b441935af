#pragma once
/// Non-fatal findings about user input, such as a PLY header line raylab does not know (an
/// exporter's "Created by ..." line) or faces a loader cannot use: the input is read anyway and
/// the finding printed to stderr as one line `raylab: warning: <message>` (control characters
/// escaped as in InputError), so that nothing is dropped silently.
#include <string>

namespace raylab {

/// Prints `message` as one warning line; safe to call from several threads.
void warn_input(const std::string& message);

/// Prints `message` as warn_input does the first time this process passes `key`, and nothing
/// after (a sweep or an experiment's rounds build the same structure many times).
void warn_input_once(const std::string& key, const std::string& message);

}  // namespace raylab
