#include "harness/outputs/csv_writer.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace ricochet {

void append_number(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "nan";  // to_chars would write "-nan" for a NaN with its sign bit set
    return;
  }
  if (std::isinf(value)) {
    out += value > 0 ? "inf" : "-inf";
    return;
  }
  char buffer[32];  // the longest shortest form, "-2.2250738585072014e-308", has 24 characters
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (ec != std::errc{}) throw std::logic_error("append_number: to_chars buffer too small");
  out.append(buffer, end);
}

std::string csv_field(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  quoted += '"';
  return quoted;
}

std::string format_csv(const std::vector<std::string>& columns,
                       const std::vector<double>& rows_row_major) {
  const std::size_t k = columns.size();
  if (k == 0) throw std::invalid_argument("format_csv: no columns");
  if (rows_row_major.size() % k != 0) {
    throw std::invalid_argument("format_csv: " + std::to_string(rows_row_major.size()) +
                                " values are not a whole number of rows of " +
                                std::to_string(k) + " columns");
  }
  std::string out;
  for (std::size_t j = 0; j < k; ++j) {
    if (j > 0) out += ',';
    out += csv_field(columns[j]);
  }
  out += '\n';
  for (std::size_t i = 0; i < rows_row_major.size(); ++i) {
    append_number(out, rows_row_major[i]);
    out += (i + 1) % k == 0 ? '\n' : ',';
  }
  return out;
}

}  // namespace ricochet
