#pragma once
/// RFC 4180 CSV, as the lab writes and reads it: fields separated by commas, a field holding a
/// comma, a quote or a line break wrapped in quotes with its quotes doubled, rows ended by '\n'.
#include <string>
#include <string_view>
#include <vector>

namespace raylab {

/// `text` as one CSV field: unchanged unless it needs quoting.
std::string csv_field(std::string_view text);

/// Splits one row (without its line end) into fields. Returns false on an unterminated quote or
/// text after a closing quote.
bool split_csv_row(std::string_view row, std::vector<std::string>& fields);

}  // namespace raylab
