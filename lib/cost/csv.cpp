#include "cost/csv.h"

namespace raylab {

std::string csv_field(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string q = "\"";
  for (char c : text) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

bool split_csv_row(std::string_view row, std::vector<std::string>& fields) {
  fields.clear();
  std::string field;
  std::size_t i = 0;
  for (;;) {
    field.clear();
    if (i < row.size() && row[i] == '"') {
      ++i;
      for (;;) {
        if (i >= row.size()) return false;  // unterminated quote
        if (row[i] == '"') {
          if (i + 1 < row.size() && row[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          ++i;
          break;
        }
        field += row[i++];
      }
      if (i < row.size() && row[i] != ',') return false;  // text after the closing quote
    } else {
      while (i < row.size() && row[i] != ',') {
        if (row[i] == '"') return false;  // a quote inside an unquoted field
        field += row[i++];
      }
    }
    fields.push_back(field);
    if (i >= row.size()) return true;
    ++i;  // the comma
  }
}

}  // namespace raylab
